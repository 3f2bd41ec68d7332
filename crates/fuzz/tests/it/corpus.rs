//! The fuzzer's corpus (seeds and every input that once failed) replayed:
//! no panic, no non-finite or null result, and each within a few seconds.

use limpid_fuzz::{corpus, execute, Outcome};

#[test]
fn every_corpus_input_ends_in_an_error_or_a_finite_result() {
    let inputs = corpus();
    assert!(inputs.len() >= 10, "corpus has {} inputs", inputs.len());
    let mut accepted = 0;
    for (name, bytes) in &inputs {
        let start = std::time::Instant::now();
        let outcome = execute(name, bytes);
        assert!(
            !matches!(outcome, Outcome::Finding(_)),
            "{name}: {outcome:?}"
        );
        assert!(
            start.elapsed().as_secs() < 10,
            "{name} took {:?}",
            start.elapsed()
        );
        accepted += usize::from(outcome == Outcome::Accepted);
    }
    // the seeds are valid inputs: most of them must be accepted, or the fuzzer
    // would only exercise the first line of each reader
    let seeds = std::fs::read_dir(limpid_fuzz::corpus_dir().join("seeds"))
        .unwrap()
        .count();
    assert!(
        accepted * 10 >= seeds * 8,
        "only {accepted} of {seeds} seeds accepted"
    );
}
