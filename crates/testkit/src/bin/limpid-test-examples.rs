//! Write limpid's example recordings (every family, with their truth files)
//! into a folder, for the Python tests and for anyone who wants them:
//! `cargo run -p limpid-testkit --bin limpid-test-examples -- DIR`.

fn main() {
    let mut args = std::env::args_os().skip(1);
    let (Some(dir), None) = (args.next(), args.next()) else {
        eprintln!("usage: limpid-test-examples DIR");
        std::process::exit(2);
    };
    let dir = std::path::PathBuf::from(dir);
    if let Err(e) = limpid_testkit::examples::write_all(&dir) {
        eprintln!("limpid-test-examples: {}: {e}", dir.display());
        std::process::exit(1);
    }
}
