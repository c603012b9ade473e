fn main() {
    let spec = std::env::args().nth(1).unwrap_or("ur10e".into());
    let cell = deflex_sim::CellConfig::for_robot(&spec).unwrap();
    println!("{}", toml::to_string(&cell).unwrap());
}
