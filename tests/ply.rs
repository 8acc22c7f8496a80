//! The PLY reader on whole files: ASCII and both binary byte orders, extra properties skipped,
//! and every malformed input an error that names it (never a panic or a huge allocation).

use fovea::scene::{parse_ply, PlyError};
use glam::Vec3;

fn quad_ply(face_index: i32) -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\ncomment test\nelement vertex 4\n\
property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for (x, y) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for c in [x, y, 0.0] {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b.push(255);
    }
    b.push(4);
    for i in [0, 1, 2, face_index] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b
}

#[test]
fn quad_becomes_two_triangles_and_extra_properties_are_skipped() {
    let m = parse_ply(&quad_ply(3)).unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(m.indices, vec![0, 1, 2, 0, 2, 3]);
}

#[test]
fn bad_files_say_what_is_wrong() {
    assert_eq!(parse_ply(b"solid stl"), Err(PlyError::NotPly));
    assert_eq!(
        parse_ply(&quad_ply(9)),
        Err(PlyError::IndexOutOfRange {
            face: 0,
            index: 9,
            count: 4
        })
    );
    let mut short = quad_ply(3);
    short.truncate(short.len() - 3);
    assert_eq!(parse_ply(&short), Err(PlyError::Truncated("faces")));
    let odd = b"ply\nformat binary_middle_endian 1.0\nelement vertex 0\nend_header\n";
    assert_eq!(
        parse_ply(odd),
        Err(PlyError::Format("binary_middle_endian".into()))
    );
}

#[test]
fn ascii_and_big_endian_read_the_same_quad() {
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
    let le = parse_ply(&quad_ply(3)).unwrap();
    assert_eq!(parse_ply(ascii).unwrap(), le);
    let mut be = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\n\
property float y\nproperty float z\nproperty uchar red\nelement face 1\n\
property list uchar int vertex_indices\nend_header\n"
        .to_vec();
    for (x, y) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for c in [x, y, 0.0] {
            be.extend_from_slice(&c.to_be_bytes());
        }
        be.push(7);
    }
    be.push(4);
    for i in [0i32, 1, 2, 3] {
        be.extend_from_slice(&i.to_be_bytes());
    }
    assert_eq!(parse_ply(&be).unwrap(), le);
}

#[test]
fn lying_counts_are_refused_before_allocating() {
    let huge = b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n\
property float x\nproperty float y\nproperty float z\nend_header\n";
    assert!(matches!(
        parse_ply(huge),
        Err(PlyError::TooMany {
            count: 1_000_000_000,
            ..
        })
    ));
    let more = b"ply\nformat ascii 1.0\nelement vertex 1000\nproperty float x\n\
property float y\nproperty float z\nend_header\n0 0 0\n";
    assert_eq!(parse_ply(more), Err(PlyError::Truncated("vertices")));
    let list = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\n\
end_header\n0 0 0 1 0 0 0 1 0 4000000000 0 1 2\n";
    assert_eq!(parse_ply(list), Err(PlyError::Truncated("faces")));
    let nan = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\n\
end_header\n0 0 0 1 nan 0 0 1 0\n";
    assert_eq!(parse_ply(nan), Err(PlyError::NonFinite(1)));
    let word = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n\
property float y\nproperty float z\nend_header\n0 zero 0\n";
    assert!(matches!(parse_ply(word), Err(PlyError::BadNumber { .. })));
}

#[test]
fn degenerate_faces_are_dropped_and_counted() {
    let text = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
property float y\nproperty float z\nelement face 3\nproperty list uchar int vertex_indices\n\
end_header\n0 0 0\n1 0 0\n0 1 0\n2 0 0\n3 0 1 2\n3 0 0 1\n3 0 1 3\n";
    let m = parse_ply(text).unwrap();
    assert_eq!(m.indices, vec![0, 1, 2]);
    assert_eq!(
        m.dropped_degenerate, 2,
        "a repeated corner and a collinear triple"
    );
}

#[test]
fn shipped_bunny_matches_its_credit_line() {
    let m = parse_ply(include_bytes!("../assets/meshes/bunny.ply")).unwrap();
    assert_eq!(m.positions.len(), 1839);
    assert_eq!(m.indices.len(), 3674 * 3);
}
