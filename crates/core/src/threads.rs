//! How many worker threads a run may ask for. Each thread reserves a stack
//! and is started before any work: 100 000 of them took a minute before the
//! first sample was read (issue 76), so a request beyond any machine limpid
//! runs on is refused, naming where it came from.

/// The most threads a pool may have: far above any 2-256-core machine's
/// cores, far below where starting them costs more than the work.
pub const MAX_THREADS: usize = 1024;

/// `n` threads asked for by `source` (a flag, an environment variable or a
/// keyword): accepted when 1..=[`MAX_THREADS`].
pub fn check_thread_count(n: u128, source: &str) -> Result<usize, String> {
    let named = if source.ends_with('=') {
        format!("{source}{n}")
    } else {
        format!("{source} {n}")
    };
    if n == 0 {
        return Err(format!("{named}: expected at least 1 thread"));
    }
    if n > MAX_THREADS as u128 {
        return Err(format!(
            "{named}: at most {MAX_THREADS} threads (each one is started before any work; one a core is the default)"
        ));
    }
    Ok(n as usize)
}

/// `RAYON_NUM_THREADS` as rayon reads it (a whole number; 0 or unset: one a
/// core), checked: `Ok(None)` when rayon's default applies.
pub fn environment_thread_count() -> Result<Option<usize>, String> {
    let Ok(text) = std::env::var("RAYON_NUM_THREADS") else {
        return Ok(None);
    };
    match text.trim().parse::<u128>() {
        Ok(0) => Ok(None),
        Ok(n) => check_thread_count(n, "RAYON_NUM_THREADS=").map(Some),
        // rayon ignores what is not a number; so do we
        Err(_) => Ok(None),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_beyond_the_cap_are_refused_naming_their_source() {
        assert_eq!(check_thread_count(2, "--threads").unwrap(), 2);
        assert_eq!(check_thread_count(1024, "--threads").unwrap(), 1024);
        let e = check_thread_count(100_000, "--threads").unwrap_err();
        assert!(e.starts_with("--threads 100000: at most 1024"), "{e}");
        let e = check_thread_count(1 << 63, "threads=").unwrap_err();
        assert!(e.contains("at most 1024"), "{e}");
        assert!(check_thread_count(0, "--threads").is_err());
    }
}
