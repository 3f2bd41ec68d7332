//! Welch PSD, CSD and coherence against scipy.signal 1.17 (fixture made by
//! fixtures/make_scipy_spectral.py), and multiple coherence of a MIMO system.

use limpid_dsp::spectral::{
    coherence, csd, mimo_point, psd, Detrend, Scaling, SegmentSpectra, Welch, Window,
};
use serde_json::Value;

use crate::common::{max_rel, vec_of};

#[test]
fn welch_csd_coherence_match_scipy() {
    let f: Value = serde_json::from_str(include_str!("../fixtures/scipy_spectral.json")).unwrap();
    let (x, y) = (vec_of(&f["x"]), vec_of(&f["y"]));
    for case in f["cases"].as_array().unwrap() {
        let p = &case["params"];
        let mut w = Welch::new(f["fs"].as_f64().unwrap());
        if let Some(n) = p["nperseg"].as_u64() {
            w.nperseg = n as usize;
        }
        w.noverlap = p["noverlap"].as_u64().map(|v| v as usize);
        w.window = match p["window"].as_str() {
            Some("hamming") => Window::Hamming,
            Some("boxcar") => Window::Boxcar,
            _ => Window::Hann,
        };
        w.detrend = match p["detrend"].as_str() {
            Some("linear") => Detrend::Linear,
            Some("none") => Detrend::None,
            _ => Detrend::Constant,
        };
        w.scaling = if p["scaling"].as_str() == Some("spectrum") {
            Scaling::Spectrum
        } else {
            Scaling::Density
        };
        let (freq, pxx) = psd(&x, &w).unwrap();
        assert!(max_rel(&freq, &vec_of(&case["f"])) < 1e-12);
        assert!(max_rel(&pxx, &vec_of(&case["pxx"])) < 1e-10, "psd {p}");
        let (_, pxy) = csd(&x, &y, &w).unwrap();
        let re: Vec<f64> = pxy.iter().map(|c| c.re).collect();
        let im: Vec<f64> = pxy.iter().map(|c| c.im).collect();
        let scale = vec_of(&case["pxy_re"])
            .iter()
            .chain(vec_of(&case["pxy_im"]).iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let err = re
            .iter()
            .zip(vec_of(&case["pxy_re"]))
            .chain(im.iter().zip(vec_of(&case["pxy_im"])))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs() / scale));
        assert!(err < 1e-10, "csd {p}: {err:e}");
        let wc = Welch {
            scaling: Scaling::Density,
            ..w.clone()
        };
        let (_, cxy) = coherence(&x, &y, &wc).unwrap();
        assert!(
            max_rel(&cxy, &vec_of(&case["cxy"])) < 1e-10,
            "coherence {p}"
        );
    }
}

/// Uniform numbers in [-0.5, 0.5) from a xorshift generator (no rand in this crate's tests).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state as f64 / u64::MAX as f64) - 0.5
    }
}

#[test]
fn multiple_coherence_is_one_without_noise_and_drops_as_predicted() {
    // two independent inputs, two outputs: y1 = u1 + 0.5 u2 (+ noise), y2 = u2 delayed
    let n = 40_000;
    let mut rnd = uniform(12345);
    let u1: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let u2: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let noise: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let y2: Vec<f64> = (0..n)
        .map(|i| if i >= 3 { u2[i - 3] } else { 0.0 })
        .collect();
    let w = Welch {
        nperseg: 256,
        ..Welch::new(1000.0)
    };
    for (sigma, expected) in [(0.0, 1.0), (1.0, 1.25 / 2.25)] {
        let y1: Vec<f64> = (0..n)
            .map(|i| u1[i] + 0.5 * u2[i] + sigma * noise[i])
            .collect();
        let spectra = SegmentSpectra::new(&[&u1, &u2, &y1, &y2], &w).unwrap();
        let mats = spectra.matrix();
        let mut mean_coh = 0.0;
        let mut mean_h = 0.0;
        let bins = 20..100;
        for k in bins.clone() {
            let p = mimo_point(&mats[k], 2).unwrap();
            mean_coh += p.multiple[0];
            // a 3-sample delay in 256-sample segments loses ~2 x 3/256 of the coherence (segment edges)
            assert!(p.multiple[1] > 0.97, "delayed output: {}", p.multiple[1]);
            mean_h += p.h[(0, 0)].re;
            if sigma == 0.0 {
                assert!((p.h[(0, 1)] - num_complex::Complex64::new(0.5, 0.0)).norm() < 1e-9);
                assert!(
                    (p.partial[0][0] - 1.0).abs() < 1e-9 && (p.partial[0][1] - 1.0).abs() < 1e-9
                );
            }
        }
        mean_coh /= bins.len() as f64;
        mean_h /= bins.len() as f64;
        assert!(
            (mean_h - 1.0).abs() < if sigma == 0.0 { 1e-9 } else { 0.05 },
            "H11 {mean_h}"
        );
        // signal power 1.25 var(u), noise power var(u): coherence 1.25 / 2.25 with noise
        assert!(
            (mean_coh - expected).abs() < 0.03,
            "sigma {sigma}: mean multiple coherence {mean_coh}"
        );
    }
}

#[test]
fn nearly_coherent_inputs_give_no_response_instead_of_rounding_noise() {
    // u2 = u1 up to 1e-9: G_uu is singular to working precision at every frequency
    let n = 8192;
    let mut rnd = uniform(99);
    let u1: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let u2: Vec<f64> = u1.iter().map(|v| v + 1e-9 * rnd()).collect();
    let y: Vec<f64> = u1.iter().zip(&u2).map(|(a, b)| a - 2.0 * b).collect();
    let w = Welch {
        nperseg: 256,
        ..Welch::new(1000.0)
    };
    let mats = SegmentSpectra::new(&[&u1, &u2, &y], &w).unwrap().matrix();
    assert!(mats[1..].iter().all(|m| mimo_point(m, 2).is_none()));
    // with u2 independent the same system is identified exactly
    let u2: Vec<f64> = (0..n).map(|_| rnd()).collect();
    let y: Vec<f64> = u1.iter().zip(&u2).map(|(a, b)| a - 2.0 * b).collect();
    let mats = SegmentSpectra::new(&[&u1, &u2, &y], &w).unwrap().matrix();
    for m in &mats[1..] {
        let p = mimo_point(m, 2).expect("independent inputs");
        assert!((p.h[(0, 1)].re + 2.0).abs() < 1e-9 && (p.multiple[0] - 1.0).abs() < 1e-9);
    }
}

/// The jackknife's replicates from one pass over the segments equal the
/// spectral matrix averaged without each group, computed directly.
#[test]
fn jackknife_replicates_equal_the_matrix_without_each_group() {
    let n = 6000;
    let signal = |a: f64, b: f64| -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64;
                (a * t).sin() + 0.5 * (b * t * t * 1e-4).cos() + 1e-3 * ((i * 7919) % 101) as f64
            })
            .collect()
    };
    let (u, v, y) = (signal(0.3, 1.1), signal(0.17, 2.3), signal(0.05, 0.7));
    let mut w = Welch::new(100.0);
    w.nperseg = 256;
    let spectra = SegmentSpectra::new(&[&u, &v, &y], &w).unwrap();
    let segments = spectra.segments();
    assert!(segments > 30);
    // uneven groups, and the last segments in no group
    let groups: Vec<std::ops::Range<usize>> = vec![0..3, 3..10, 10..11, 11..segments - 4];
    let bins = 40;
    let fast = spectra.matrices_deleting(bins, &groups);
    assert_eq!(fast.len(), groups.len());
    // subtracting a group from the total loses digits in proportion to the
    // total over what is kept: compare against the full matrix's size
    let full = spectra.matrix_below(bins, 0..0);
    for (g, replicate) in groups.iter().zip(&fast) {
        let direct = spectra.matrix_below(bins, g.clone());
        assert_eq!(replicate.len(), bins);
        for ((a, b), f) in replicate.iter().zip(&direct).zip(&full) {
            let scale = f
                .iter()
                .chain(b.iter())
                .map(|z| z.norm())
                .fold(0.0, f64::max);
            for (x, z) in a.iter().zip(b.iter()) {
                assert!((x - z).norm() <= 1e-11 * scale, "group {g:?}: {x} vs {z}");
            }
        }
    }
}
