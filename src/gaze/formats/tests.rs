use super::*;

#[test]
fn non_finite_values_are_refused_or_missing_never_used() {
    let generic = |text: &str| {
        let opts = ParseOptions {
            format: Some(Format::Generic),
            ..ParseOptions::default()
        };
        parse(text, &opts)
    };
    let head = "t_ms,x,y\n";
    for bad_time in ["inf", "-inf", "nan", "-nan", "1e400"] {
        let text = format!("{head}0,0.5,0.5\n{bad_time},0.5,0.5\n");
        assert!(generic(&text).is_err(), "time {bad_time}");
    }
    let far = generic(&format!("{head}0,0.5,0.5\n1e300,0.5,0.5\n"));
    assert!(
        matches!(far, Err(FormatError::TooLong { line: 3, .. })),
        "{far:?}"
    );
    let rec = generic(&format!("{head}0,-nan,0.5\n1,0.5,inf\n2,0.5,0.5\n")).unwrap();
    let xy: Vec<_> = rec.samples.iter().map(|s| s.xy).collect();
    assert_eq!(xy, [None, None, Some([0.5, 0.5])]);
}

fn eyelink() -> ParseOptions {
    ParseOptions {
        screen: Some((1920, 1200)),
        ..Default::default()
    }
}

/// The first 1.2 s of the real 500 Hz EyeLink recording cut around a blink (from 2.012 s).
const EXCERPT: &str = "t_s,xpos,ypos,ps\n0.000,952.8,593.5,1068.0\n0.002,952.6,593.6,1068.0\n2.002,1092.1,564.8,1072.0\n2.012,,,0.0\n2.014,,,0.0\n2.100,2400.0,-30.0,1000.0\n";

#[test]
fn eyelink_excerpt_with_a_blink_and_an_off_screen_sample() {
    let r = parse(EXCERPT, &eyelink()).unwrap();
    assert_eq!(r.format, Format::Eyelink);
    assert_eq!(r.samples.len(), 6);
    assert_eq!(r.samples[0].t_ms, 0.0);
    assert!((r.samples[2].t_ms - 2002.0).abs() < 1e-9);
    let [x, y] = r.samples[0].xy.unwrap();
    assert!((x - 952.8 / 1920.0).abs() < 1e-12 && (y - 593.5 / 1200.0).abs() < 1e-12);
    assert_eq!(r.samples[3].xy, None, "track loss");
    assert_eq!(r.samples[3].pupil_mm, None, "blink: pupil 0");
    assert!(
        super::super::sendable(&r.samples[5]).is_none(),
        "far off screen: not sent"
    );
    // Median area 1068 maps to 4 mm.
    assert!((r.samples[0].pupil_mm.unwrap() - 4.0).abs() < 1e-9);
    assert!(r.pupil_rule.unwrap().contains("√area"));
}

#[test]
fn the_shipped_recordings_parse() {
    for (file, w, h, n) in [
        (
            "../../assets/gaze/eyelink_500hz_1920x1200.csv",
            1920,
            1200,
            14_353,
        ),
        (
            "../../assets/gaze/eyelink_1000hz_1920x1080.csv",
            1920,
            1080,
            66_827,
        ),
    ] {
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("src/gaze")
                .join(file),
        )
        .unwrap();
        let r = parse(
            &text,
            &ParseOptions {
                screen: Some((w, h)),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(r.samples.len(), n);
        let lost = r.samples.iter().filter(|s| s.xy.is_none()).count();
        assert!(lost > 0 && lost < n / 5, "track loss {lost}");
    }
}

#[test]
fn other_formats_are_detected_and_normalised() {
    let core = "gaze_timestamp,world_index,confidence,norm_pos_x,norm_pos_y\n100.0,0,0.9,0.25,0.75\n100.01,1,0.3,0.5,0.5\n";
    let r = parse(core, &ParseOptions::default()).unwrap();
    assert_eq!(r.format, Format::PupilCore);
    assert_eq!(
        r.samples[0].xy,
        Some([0.25, 0.25]),
        "bottom-left origin flipped"
    );
    assert_eq!(r.samples[1].xy, None, "low confidence is track loss");
    assert!((r.samples[1].t_ms - 10.0).abs() < 1e-6);
    let neon = "section id,recording id,timestamp [ns],gaze x [px],gaze y [px],worn\na,b,1000000000,800,600,1\na,b,1005000000,0,0,1\n";
    let r = parse(neon, &ParseOptions::default()).unwrap();
    assert_eq!(
        (r.format, r.samples[0].xy, r.samples[1].t_ms),
        (Format::PupilNeon, Some([0.5, 0.5]), 5.0)
    );
    let tobii = "device_time_stamp,gaze_point_x,gaze_point_y,pupil_diameter\n1000,0.1,0.2,3.5\n9333,0.3,0.4,-1\n";
    let r = parse(tobii, &ParseOptions::default()).unwrap();
    assert_eq!(
        (r.format, r.samples[0].pupil_mm, r.samples[1].pupil_mm),
        (Format::Tobii, Some(3.5), None)
    );
    let generic = "time,gx,gy\n0,10,20\n1,30,40\n";
    let opts = ParseOptions {
        format: Some(Format::Generic),
        screen: Some((100, 100)),
        columns: Columns {
            time: "time".into(),
            x: "gx".into(),
            y: "gy".into(),
            pupil: None,
            time_unit: "s".into(),
            pixels: true,
        },
        ..Default::default()
    };
    let r = parse(generic, &opts).unwrap();
    assert_eq!(
        (r.samples[1].t_ms, r.samples[1].xy),
        (1000.0, Some([0.3, 0.4]))
    );
}

#[test]
fn malformed_files_get_clear_errors() {
    assert_eq!(parse("", &eyelink()), Err(FormatError::Empty));
    assert_eq!(
        parse("t_s,xpos,ypos,ps\n", &eyelink()),
        Err(FormatError::NoSamples)
    );
    assert!(matches!(
        parse("a,b\n1,2\n", &eyelink()),
        Err(FormatError::Unknown { .. })
    ));
    let e = parse("t_s,xpos,ypos,ps\n0.0,abc,1,1\n", &eyelink()).unwrap_err();
    assert_eq!(
        e,
        FormatError::NotNumeric {
            line: 2,
            column: "xpos".into(),
            value: "abc".into()
        }
    );
    assert!(matches!(
        parse("t_s,xpos,ypos,ps\n0.2,1,1,1\n0.1,1,1,1\n", &eyelink()),
        Err(FormatError::Unsorted { line: 3, .. })
    ));
    assert!(matches!(
        parse("t_s,xpos,ypos,ps\n0.2,1,1,1\n0.2,1,1,1\n", &eyelink()),
        Err(FormatError::Duplicate { line: 3, .. })
    ));
    assert_eq!(
        parse("t_s,xpos,ypos,ps\n0,1,1,1\n", &ParseOptions::default()),
        Err(FormatError::NeedsScreen(Format::Eyelink))
    );
    let missing = ParseOptions {
        format: Some(Format::Tobii),
        ..Default::default()
    };
    assert!(parse("device_time_stamp,x\n1,2\n", &missing)
        .unwrap_err()
        .to_string()
        .contains("gaze_point_x"));
}

#[test]
fn generic_csv_round_trips() {
    let samples = vec![
        Sample {
            t_ms: 0.0,
            xy: Some([0.25, 0.5]),
            pupil_mm: Some(3.5),
        },
        Sample {
            t_ms: 2.5,
            xy: None,
            pupil_mm: None,
        },
        Sample {
            t_ms: 4.0,
            xy: Some([1.0, 0.0]),
            pupil_mm: None,
        },
    ];
    let back = parse(&write_generic(&samples), &ParseOptions::default()).unwrap();
    assert_eq!(back.samples, samples);
}

#[test]
fn the_pupil_rule_names_the_median_area_as_recorded() {
    // √1103 squared back is 1102.9999999999998, which the rule used to print.
    let raw = [Some(900.0), Some(1103.0), Some(1400.0)];
    let mut samples = vec![
        Sample {
            t_ms: 0.0,
            xy: None,
            pupil_mm: None,
        };
        3
    ];
    let rule = pupil_rule(&mut samples, &raw, PupilUnit::Area, 4.0).unwrap();
    assert!(rule.contains("(median area 1103 ↦ 4 mm)"), "{rule}");
    assert!((samples[1].pupil_mm.unwrap() - 4.0).abs() < 1e-12);
    let smaller = 4.0 * (900.0f64 / 1103.0).sqrt();
    assert!((samples[0].pupil_mm.unwrap() - smaller).abs() < 1e-12);
}
