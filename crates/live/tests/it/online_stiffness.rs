//! Issue 19's acceptance on the shipped co-contraction recordings: the
//! samples go through the live processor in order (as a replay delivers
//! them), and 3 s of data after each level starts the online stiffness is
//! within 10 % (relative Frobenius) of the offline estimate of that level,
//! and stays there to the level's end; before it has a number it says why.

use limpid_analysis::cocontraction::estimate_cocontraction;
use limpid_analysis::emg::{emg_columns, mvc_maxima, EmgParams};
use limpid_ident::PrepareParams;
use limpid_live::process::Processor;

fn frobenius_error(a: &[[f64; 3]; 3], b: &limpid_core::Matrix) -> f64 {
    let (mut d, mut n) = (0.0, 0.0);
    for i in 0..3 {
        for j in 0..3 {
            d += (a[i][j] - b[(i, j)]).powi(2);
            n += b[(i, j)].powi(2);
        }
    }
    (d / n).sqrt()
}

type M3 = [[f64; 3]; 3];

struct Seen {
    level: f64,
    at_3s: Option<(M3, M3)>,
    at_end: Option<(M3, M3)>,
    status_before: Vec<String>,
}

fn replay(case: &str) -> (Vec<Seen>, Vec<(f64, limpid_core::Matrix)>) {
    let dir = limpid_testkit::examples("cocontraction");
    let rec = limpid_io::read_recording(dir.join(format!("{case}.csv"))).unwrap();
    let mvc = limpid_io::read_recording(dir.join(format!("{case}.mvc.csv"))).unwrap();
    let muscles = emg_columns(&rec);
    let maxima = mvc_maxima(&mvc, &muscles, &EmgParams::default()).unwrap();
    let offline =
        estimate_cocontraction(&rec, &mvc, &PrepareParams::default(), &EmgParams::default())
            .unwrap();
    let levels_offline: Vec<(f64, limpid_core::Matrix)> = offline
        .levels
        .iter()
        .map(|l| (l.level, l.stiffness.clone()))
        .collect();

    let fs = rec.sample_rate();
    let mut p = Processor::new(muscles.len(), fs, Some(maxima)).unwrap();
    let col = |name: &str| rec.column(name).unwrap();
    let (t, level) = (col("t"), col("level"));
    let kin: Vec<&[f64]> = ["x", "y", "z", "fx", "fy", "fz"]
        .iter()
        .map(|c| col(c))
        .collect();
    let emg: Vec<&[f64]> = muscles.iter().map(|m| col(m)).collect();
    let mut seen: Vec<Seen> = Vec::new();
    let mut level_start = f64::NAN;
    let mut e = vec![0.0; emg.len()];
    for n in 0..t.len() {
        if seen.last().is_none_or(|s| s.level != level[n]) {
            if let Some(s) = seen.last_mut() {
                s.at_end = p.online.estimate().map(|e| (e.stiffness, e.stiffness_se));
            }
            seen.push(Seen {
                level: level[n],
                at_3s: None,
                at_end: None,
                status_before: Vec::new(),
            });
            level_start = t[n];
        }
        for (v, c) in e.iter_mut().zip(&emg) {
            *v = c[n];
        }
        let k = [
            kin[0][n], kin[1][n], kin[2][n], kin[3][n], kin[4][n], kin[5][n],
        ];
        p.update(&e, Some(&k));
        let s = seen.last_mut().unwrap();
        let since = t[n] - level_start;
        if since < 3.0 && n % 100 == 0 {
            let view = limpid_live::server::OnlineView::of(&p);
            assert_eq!(
                view.stiffness.is_some(),
                view.status == "estimating",
                "{view:?}"
            );
            s.status_before.push(view.status);
        }
        if since >= 3.0 && s.at_3s.is_none() {
            let view = limpid_live::server::OnlineView::of(&p);
            s.at_3s = Some((
                view.stiffness.unwrap_or_else(|| {
                    panic!(
                        "{case} level {}: no stiffness 3 s in: {}",
                        s.level, view.status
                    )
                }),
                view.stiffness_se.unwrap(),
            ));
        }
    }
    seen.last_mut().unwrap().at_end = p.online.estimate().map(|e| (e.stiffness, e.stiffness_se));
    assert_eq!(
        p.level_changes as usize,
        seen.len() - 1,
        "{case}: one restart per level change"
    );
    (seen, levels_offline)
}

fn check(case: &str) {
    let (seen, offline) = replay(case);
    for s in &seen {
        let (_, k_off) = offline.iter().find(|(l, _)| *l == s.level).unwrap();
        let (k3, se3) = s.at_3s.unwrap();
        let e3 = frobenius_error(&k3, k_off);
        let (end, se_end) = s.at_end.expect("an estimate at the level's end");
        let e_end = frobenius_error(&end, k_off);
        let se_rel = norm(&se3) / k_off.0.norm();
        let se_rel_end = norm(&se_end) / k_off.0.norm();
        println!(
            "{case} level {}: online vs offline K {:.1} % after 3 s, {:.1} % at the end; SE/|K| {:.1} % after 3 s, {:.1} % at the end; before 3 s: {:?}",
            s.level,
            100.0 * e3,
            100.0 * e_end,
            100.0 * se_rel,
            100.0 * se_rel_end,
            s.status_before.iter().collect::<std::collections::BTreeSet<_>>()
        );
        assert!(
            e3 < 0.10,
            "{case} level {}: {:.1} % after 3 s",
            s.level,
            100.0 * e3
        );
        assert!(
            e_end < 0.10,
            "{case} level {}: {:.1} % at the end",
            s.level,
            100.0 * e_end
        );
        assert!(s
            .status_before
            .iter()
            .any(|w| w.starts_with("waiting for perturbations")));
    }
}

fn norm(a: &[[f64; 3]; 3]) -> f64 {
    a.iter().flatten().map(|v| v * v).sum::<f64>().sqrt()
}

#[test]
fn online_stiffness_of_config4_follows_the_offline_estimate_per_level() {
    check("ex_config4");
}

#[test]
fn online_stiffness_of_config7_follows_the_offline_estimate_per_level() {
    check("ex_config7");
}
