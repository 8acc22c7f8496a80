fn main() {
    let path = std::path::PathBuf::from(std::env::args().nth(1).unwrap());
    let folder = fovea::scene::Folder::open(path.parent().unwrap()).unwrap();
    let s = fovea::scene::Scene::load(&path, &folder).unwrap();
    println!(
        "camera {:?}\nlight {:?}\nlights {:?}\nmm {}",
        s.file.camera, s.file.light, s.file.lights, s.file.mm_per_unit
    );
    println!("bounds {:?}", s.mesh.bounds());
}
