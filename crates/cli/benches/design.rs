//! Criterion benchmark of experiment design (issue 60: under 10 s for the
//! 3-D linear method): `limpid protocol design --prior demo:S1 --limits-from
//! artemiadis-3d --duration 147.2` with the default 40 recordings behind the
//! prediction, the stochastic method's end-point multisine (the
//! endpoint-multisine preset's limits), the reflex method's PRBS design on
//! the virtual ankle and the planar method's (`demo:planar`, lakatos-planar's
//! limits, 72 s).

use criterion::{criterion_group, criterion_main, Criterion};
use limpid_app::design::reflex::{design_reflex, ReflexDesignRequest, ReflexPrior};
use limpid_app::design::stochastic::{design_stochastic, StochasticDesignRequest};
use limpid_app::design::{design, DesignRequest, Objective, Prior};

fn bench(c: &mut Criterion) {
    let seed = limpid_lab::protocol::preset("artemiadis-3d").expect("preset");
    let linear = DesignRequest {
        prior: Prior::demo(0),
        limits: seed.limits.clone(),
        sample_rate_hz: seed.sample_rate_hz,
        budget_s: 147.2,
        objective: Objective::default(),
        runs: 40,
        baseline: None,
        verify: 0,
        seed: 1,
    };
    let multisine = limpid_lab::periodic::PeriodicDesign::multisine_endpoint();
    let stochastic = StochasticDesignRequest {
        prior: Prior::demo(0),
        limits: multisine.limits.clone(),
        sample_rate_hz: multisine.sample_rate_hz,
        budget_s: 147.2,
        objective: Objective::default(),
        runs: 40,
        baseline: None,
        verify: 0,
        seed: 1,
    };
    let mut prbs = limpid_lab::periodic::PeriodicDesign::prbs_joint();
    prbs.limits.max_joint_displacement_rad = Some(0.03);
    let reflex = ReflexDesignRequest {
        prior: ReflexPrior::demo(),
        limits: prbs.limits.clone(),
        sample_rate_hz: prbs.sample_rate_hz,
        budget_s: 95.25,
        runs: 40,
        baseline: None,
        seed: 1,
    };
    let lakatos = limpid_lab::design::PlanarDesign::seed003();
    let planar = limpid_app::design::planar::PlanarDesignRequest {
        prior: limpid_app::design::planar::PlanarPrior::demo(),
        limits: limpid_app::design::planar::PlanarFrame {
            limits: lakatos.limits.clone(),
            link_lengths_m: lakatos.link_lengths_m,
            posture_rad: lakatos.posture_rad,
            wait_s: lakatos.wait_s,
        },
        sample_rate_hz: lakatos.sample_rate_hz,
        budget_s: 72.0,
        objective: Objective::default(),
        runs: 40,
        baseline: None,
        verify: 0,
        seed: 1,
    };
    let mut group = c.benchmark_group("design");
    group.sample_size(10);
    group.bench_function("linear_s1_147s", |b| {
        b.iter(|| design(&linear).expect("design"))
    });
    group.bench_function("stochastic_multisine_s1_147s", |b| {
        b.iter(|| design_stochastic(&stochastic).expect("design"))
    });
    group.bench_function("reflex_prbs_95s", |b| {
        b.iter(|| design_reflex(&reflex).expect("design"))
    });
    group.bench_function("planar_demo_72s", |b| {
        b.iter(|| limpid_app::design::planar::design_planar(&planar).expect("design"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
