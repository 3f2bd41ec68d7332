//! The parameter-varying ankle's part of `limpid calibrate` alone (issue
//! 58): coverage of K and B with and without the floors, reflex claims:
//! `cargo run --profile ci -p limpid-app --example scheduled_coverage -- 40 3`
fn main() {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(40);
    let seed: u64 = args.next().and_then(|a| a.parse().ok()).unwrap_or(3);
    let (method, claims) = limpid_app::calibrate::calibrate_scheduled(n, seed, &|| {});
    println!(
        "{}",
        serde_json::to_string_pretty(&method).unwrap_or_default()
    );
    println!("{}", serde_json::to_string(&claims).unwrap_or_default());
}
