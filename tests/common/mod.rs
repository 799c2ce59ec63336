//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod direct;

use lumest::cases::sobolev::{SobolevCase, sobolev_case};
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::{RunConfig, RunResult, Stop};
pub use lumest::tally::zcheck;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// A Sobolev case with `n` points and a run of `chains` chains.
pub fn sobolev_run(
    p: (f64, f64, f64, f64),
    n: usize,
    r_max: f64,
    cfg: &RunConfig,
) -> (SobolevCase, RunResult) {
    let s = Sobolev::new(p.0, p.1, p.2, p.3, 1.0).unwrap();
    let case = sobolev_case(&s, n, r_max);
    let rec = Receivers::new(&case.scene, &case.points).unwrap();
    let r = run(&case.scene, &rec, cfg, &mut |_| true);
    (case, r)
}

/// A configuration with a fixed number of chains.
pub fn chains_cfg(chains: u64, seed: u64, threads: usize) -> RunConfig {
    RunConfig {
        seed,
        threads,
        stop: Stop {
            chains: Some(chains),
            ..Stop::default()
        },
        ..RunConfig::default()
    }
}

/// z score of point `j` against an exact total `exact` \[lx\], by the rules
/// of [`zcheck`]: NaN for a non-finite number, and with zero standard error
/// 0 only when the estimate is exact (otherwise infinite), so that it fails
/// any bound.
pub fn z(r: &RunResult, j: usize, exact: f64) -> f64 {
    let w = &r.tallies.estimated[j];
    zcheck::z_score(r.direct[j] + w.mean(), w.std_error(), exact)
}

/// Two runs' estimates at point `j` \[lx\] (exact direct plus tallied, each)
/// and the standard error of their difference, for a z test of agreement.
pub fn apart(a: &RunResult, b: &RunResult, j: usize) -> (f64, f64, f64) {
    let e = |r: &RunResult| r.direct[j] + r.tallies.estimated[j].mean();
    let se = (a.tallies.estimated[j].std_error().powi(2)
        + b.tallies.estimated[j].std_error().powi(2))
    .sqrt();
    (e(a), e(b), se)
}

/// Largest `|z|` over `zs`, NaN if any is NaN ([`zcheck::max_abs_z`];
/// `f64::max` would drop a NaN); test it with [`zcheck::within`].
pub fn max_abs_z(zs: impl IntoIterator<Item = f64>) -> f64 {
    zcheck::max_abs_z(zs)
}

/// Pearson's statistic with pooling of cells whose expected count is < 5.
/// Returns the p-value `P[χ²_dof > stat]`; panics if a cell with zero
/// expectation received samples.
pub fn chi2_pvalue(observed: &[f64], expected: &[f64]) -> (f64, f64, usize) {
    assert_eq!(observed.len(), expected.len());
    let mut cells: Vec<(f64, f64)> = observed
        .iter()
        .copied()
        .zip(expected.iter().copied())
        .collect();
    for &(o, e) in &cells {
        assert!(
            !(e == 0.0 && o > 0.0),
            "{o} samples in a cell of zero expected mass"
        );
    }
    // Sort by expectation; pool the small ones (and, if the pool ends up
    // below 5, merge it into the next-smallest cell).
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut bins: Vec<(f64, f64)> = Vec::new();
    for (o, e) in cells {
        if e < 5.0 || (pool_e > 0.0 && pool_e < 5.0) {
            pool_o += o;
            pool_e += e;
        } else {
            bins.push((o, e));
        }
    }
    if pool_e > 0.0 {
        bins.push((pool_o, pool_e));
    }
    let stat: f64 = bins.iter().map(|&(o, e)| (o - e) * (o - e) / e).sum();
    let dof = bins.len() - 1;
    let p = ChiSquared::new(dof as f64).unwrap().sf(stat);
    (p, stat, dof)
}

/// Reflected illuminance \[lx\] at height `dz` above the source's foot on the
/// floor (reflectance `rho`, illuminance `e(s)`), facing it: a 1-D integral
/// over the distance `s` with panels graded at the scale `dz`.
pub fn from_floor(rho: f64, dz: f64, e: impl Fn(f64) -> f64) -> f64 {
    let rule = gauss_quad::legendre::GaussLegendre::new(std::num::NonZeroUsize::new(30).unwrap());
    let f = |s: f64| rho * e(s) * dz * dz / (s * s + dz * dz).powi(2) * 2.0 * s;
    let mut edges = vec![0.0];
    let mut x = dz / 64.0;
    while x < 64.0 {
        edges.push(x);
        x *= 2.0;
    }
    edges
        .windows(2)
        .map(|w| rule.integrate(w[0], w[1], f))
        .sum()
}

/// How `shards` shards that run at once on threads share batches, as MPI
/// ranks do through an all-gather ([`lumest::run::Share`]): every call
/// returns every shard's batches of that call, and may be repeated (the
/// pool is emptied once every shard has its copy).
pub fn share_through_memory(shards: usize) -> lumest::run::Share {
    let pool = std::sync::Arc::new((
        std::sync::Mutex::new(Vec::new()),
        std::sync::Barrier::new(shards),
    ));
    lumest::run::Share(std::sync::Arc::new(move |own| {
        pool.0.lock().unwrap().extend(own);
        pool.1.wait();
        let all = pool.0.lock().unwrap().clone();
        pool.1.wait();
        if pool.1.wait().is_leader() {
            pool.0.lock().unwrap().clear();
        }
        pool.1.wait();
        all
    }))
}

/// A room `[0, a] x [0, b] x [0, c]` as six Lambertian rectangles facing
/// in (scene text): floor, ceiling, x = 0, x = a, y = 0, y = b, with the
/// reflectances `rho` in that order.
pub fn rectangle_room([a, b, c]: [f64; 3], rho: [f64; 6]) -> String {
    let faces = [
        ([0.0, 0.0, 0.0], [a, 0.0, 0.0], [0.0, b, 0.0]),
        ([0.0, 0.0, c], [0.0, b, 0.0], [a, 0.0, 0.0]),
        ([0.0, 0.0, 0.0], [0.0, b, 0.0], [0.0, 0.0, c]),
        ([a, 0.0, 0.0], [0.0, 0.0, c], [0.0, b, 0.0]),
        ([0.0, 0.0, 0.0], [0.0, 0.0, c], [a, 0.0, 0.0]),
        ([0.0, b, 0.0], [a, 0.0, 0.0], [0.0, 0.0, c]),
    ];
    faces
        .iter()
        .zip(rho)
        .map(|((o, e1, e2), r)| {
            format!(
                "[[surface]]\ntype = \"rectangle\"\ncorner = {o:?}\nedge1 = {e1:?}\nedge2 = {e2:?}\n\
                 material = {{ type = \"lambertian\", reflectance = {r} }}\n"
            )
        })
        .collect()
}

/// Scene text of a one-sided mesh surface (reflecting on the
/// counter-clockwise side) of reflectance `rho`, its OBJ text written to
/// `dir/name`.
pub fn front_mesh(dir: &std::path::Path, name: &str, obj: &str, rho: f64) -> String {
    let path = dir.join(name);
    std::fs::write(&path, obj).unwrap();
    format!(
        "[[surface]]\ntype = \"mesh\"\nfile = {:?}\nsides = \"front\"\n\
         material = {{ type = \"lambertian\", reflectance = {rho} }}\n",
        path.display().to_string()
    )
}

/// A 1 m cube cabinet mesh `[1, 2]^2 x [0, 1]` (no bottom) standing on a
/// 10 m x 10 m floor mesh at z = 0, both two-sided, reflectance 0.5, and a
/// 100 cd point light at (0, 1.5, 2); the OBJ files written into `dir`.
pub fn cabinet_on_floor_meshes(dir: &std::path::Path) -> lumest::scene::Scene {
    std::fs::write(
        dir.join("cab.obj"),
        "v 1 1 0\nv 2 1 0\nv 2 2 0\nv 1 2 0\nv 1 1 1\nv 2 1 1\nv 2 2 1\nv 1 2 1\n\
         f 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("floor.obj"),
        "v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    lumest::scene::parse(
        r#"
[[surface]]
type = "mesh"
file = "cab.obj"
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
type = "mesh"
file = "floor.obj"
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "point"
position = [0.0, 1.5, 2.0]
intensity = 100
"#,
        &dir.join("two.toml"),
    )
    .unwrap()
}

/// OBJ text with every face wound the other way.
pub fn rewound_obj(obj: &str) -> String {
    obj.lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(f) => {
                let f: Vec<&str> = f.split_whitespace().rev().collect();
                format!("f {}\n", f.join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect()
}

/// OBJ text with every face's vertex indices moved up by `k`.
pub fn shifted_obj(obj: &str, k: u32) -> String {
    obj.lines()
        .map(|l| match l.strip_prefix("f ") {
            Some(f) => {
                let f: Vec<String> = f
                    .split_whitespace()
                    .map(|i| (i.parse::<u32>().unwrap() + k).to_string())
                    .collect();
                format!("f {}\n", f.join(" "))
            }
            None => format!("{l}\n"),
        })
        .collect()
}
