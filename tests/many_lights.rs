//! The light array (resampled importance sampling over many sources,
//! `lumest::light::array`) against the exact sum over the sources:
//! the sampled direct light at receivers, next-event estimation at
//! backward-path vertices, and bit-reproducibility for any thread count.
//! Each z-test is Sidak-corrected over its points and is shown to resolve a
//! 2 % error.

mod common;
use common::{chains_cfg, max_abs_z, zcheck};
use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::light::array::DirectLights;
use lumest::scene::{Scene, parse};
use statrs::distribution::{ContinuousCDF, Normal};
use std::path::Path;

/// Two-sided z bound for `m` tests at family-wise false-alarm rate 1e-4 (Sidak).
fn sidak(m: usize) -> f64 {
    let a = 1.0 - (1.0 - 1e-4f64).powf(1.0 / m as f64);
    Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - a / 2.0)
}

/// A hall 40 x 20 m, 4 m high (floor, ceiling and two walls as planes),
/// with 150 point lights (isotropic, 20 to 200 cd) at 3 m and 50 uniform
/// rectangular panels (0.6 x 0.6 m, facing down) at 3.9 m: 200 sources
/// whose direct light is exact (closed forms) everywhere, for any mode.
fn hall(rho: f64) -> Scene {
    let mut src = format!(
        r#"
[[surface]]
name = "floor"
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = {{ type = "lambertian", reflectance = {rho} }}
[[surface]]
name = "ceiling"
type = "plane"
point = [0, 0, 4]
normal = [0, 0, -1]
material = {{ type = "lambertian", reflectance = {rho} }}
[[surface]]
name = "wall"
type = "plane"
point = [0, 0, 0]
normal = [1, 0, 0]
material = {{ type = "lambertian", reflectance = {rho} }}
[[surface]]
name = "far wall"
type = "plane"
point = [40, 0, 0]
normal = [-1, 0, 0]
material = {{ type = "lambertian", reflectance = {rho} }}
"#
    );
    let mut u = 0x1234_5678_u64;
    let mut next = || {
        u = u
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (u >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..150 {
        let (x, y, i) = (0.5 + 39.0 * next(), 20.0 * next(), 20.0 + 180.0 * next());
        src +=
            &format!("[[light]]\ntype = \"point\"\nposition = [{x}, {y}, 3.0]\nintensity = {i}\n");
    }
    for _ in 0..50 {
        let (x, y, l) = (1.0 + 38.0 * next(), 19.0 * next(), 500.0 + 3000.0 * next());
        src += &format!(
            "[[light]]\ntype = \"rectangle\"\ncorner = [{x}, {y}, 3.9]\nedge1 = [0, 0.6, 0]\nedge2 = [0.6, 0, 0]\nluminance = {l}\n"
        );
    }
    parse(&src, Path::new("hall.toml")).unwrap()
}

/// Floor points along the hall and points on the wall (facing +x).
fn hall_points() -> Vec<(DVec3, DVec3)> {
    let mut p: Vec<(DVec3, DVec3)> = (0..16)
        .map(|k| {
            (
                DVec3::new(1.3 + 2.4 * k as f64, 3.0 + 0.9 * (k % 15) as f64, 0.0),
                DVec3::Z,
            )
        })
        .collect();
    p.extend((0..4).map(|k| (DVec3::new(0.0, 2.0 + 4.5 * k as f64, 1.5), DVec3::X)));
    p
}

/// Per-point mean and standard error of the sampled direct light over
/// `batches` batches of 256 chains (64 samples per point and batch with
/// the light array).
fn sampled_direct(scene: &Scene, rec: &Receivers, batches: u64, seed: u64) -> Vec<(f64, f64)> {
    let n = rec.len();
    let mut s = vec![(0.0, 0.0); n];
    for b in 0..batches {
        let mut out = vec![0.0; n];
        rec.sampled_direct(scene, seed, b, 256, &mut out);
        for (a, v) in s.iter_mut().zip(&out) {
            let m = v / 256.0;
            a.0 += m;
            a.1 += m * m;
        }
    }
    let b = batches as f64;
    s.iter()
        .map(|&(s1, s2)| {
            let mean = s1 / b;
            (mean, ((s2 / b - mean * mean) / (b - 1.0)).max(0.0).sqrt())
        })
        .collect()
}

/// Largest |z| of the sampled estimates `est` (mean, standard error) times
/// `scale` against the exact values.
fn scaled_max_z(est: &[(f64, f64)], exact: &[f64], scale: f64) -> f64 {
    max_abs_z(
        est.iter()
            .zip(exact)
            .map(|(&(m, se), &e)| zcheck::z_score(scale * m, scale * se, e)),
    )
}

/// Sampled RIS direct light against the exact sum (closed forms at set-up)
/// over 200 point and area sources, Sidak-corrected z over the points; the
/// same estimates 2 % off, or with the `1/M` factor dropped, fail.
#[test]
fn ris_direct_is_unbiased_against_exact_sum() {
    let scene = hall(0.5);
    let pts = hall_points();
    let exact_scene = scene.clone().with_direct_lights(DirectLights::Exact, 8);
    let exact = Receivers::new(&exact_scene, &pts).unwrap();
    assert!(!exact.has_sampled_direct(), "every source exact here");
    let ris_scene = scene.with_direct_lights(DirectLights::Ris, 8);
    assert!(ris_scene.light_array().is_some());
    let ris = Receivers::new(&ris_scene, &pts).unwrap();
    assert!(ris.direct().iter().all(|&d| d == 0.0), "all sampled");
    let est = sampled_direct(&ris_scene, &ris, 1000, 11);
    let bound = sidak(pts.len());
    let z = |scale: f64| scaled_max_z(&est, exact.direct(), scale);
    assert!(exact.direct().iter().all(|&e| e > 1.0), "every point lit");
    let z1 = z(1.0);
    assert!(zcheck::within(z1, bound), "max |z| = {z1} > {bound}");
    assert!(
        !zcheck::within(z(1.02), bound) && !zcheck::within(z(0.98), bound),
        "a 2 % error would pass: max |z| {} / {}",
        z(1.02),
        z(0.98)
    );
    let m = 8.0;
    assert!(!zcheck::within(z(m), bound) && !zcheck::within(z(1.0 / m), bound));
}

/// A weak lamp next to a point among many strong ones (0.5 cd 0.1 m above
/// the origin, 199 of 1000 cd 3 m up over a black floor): drawn by power it
/// is one candidate in 400,000 and most runs missed its 4 % of the light
/// with a steady error bar (z of -3 to -6). As a hot source of the points
/// next to it ([`lumest::light::hot_sources`]) it is drawn often, and the
/// sampled direct light agrees with the exact sum at every point.
#[test]
fn ris_finds_a_weak_lamp_next_to_the_point() {
    let mut src = String::from(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = { type = \"lambertian\", reflectance = 0 }\n\
         [[light]]\ntype = \"point\"\nposition = [0, 0, 0.1]\nintensity = 0.5\n",
    );
    for k in 1..200 {
        let a = k as f64 * 2.399_963;
        let r = 15.0 * (k as f64 / 200.0).sqrt();
        src += &format!(
            "[[light]]\ntype = \"point\"\nposition = [{}, {}, 3]\nintensity = 1000\n",
            r * a.cos() + 0.7,
            r * a.sin() - 0.4
        );
    }
    let scene = parse(&src, Path::new("weak.toml")).unwrap();
    let pts = vec![
        (DVec3::ZERO, DVec3::Z),
        (DVec3::new(0.1, 0.0, 0.0), DVec3::Z),
        (DVec3::new(5.0, 5.0, 0.0), DVec3::Z),
    ];
    let exact = Receivers::new(
        &scene.clone().with_direct_lights(DirectLights::Exact, 8),
        &pts,
    )
    .unwrap();
    let ris_scene = scene.with_direct_lights(DirectLights::Ris, 8);
    let ris = Receivers::new(&ris_scene, &pts).unwrap();
    for j in 0..2 {
        let hot = ris.hot(j).expect("RIS receivers have hot lists");
        assert!(hot.k.contains(&0), "point {j}: the weak lamp is not hot");
    }
    // The weak lamp's share at the origin: 50 of 1331 lx.
    let weak = 0.5 / (0.1 * 0.1);
    assert!(weak / exact.direct()[0] > 0.03);
    let est = sampled_direct(&ris_scene, &ris, 300, 3);
    let bound = sidak(pts.len());
    let z = |scale: f64| scaled_max_z(&est, exact.direct(), scale);
    let z1 = z(1.0);
    assert!(
        zcheck::within(z1, bound),
        "max |z| = {z1} > {bound}: {est:?}"
    );
    // Missing the weak lamp (4 % low) or a 2 % error would not pass.
    assert!(!zcheck::within(z(0.98), bound) && !zcheck::within(z(1.02), bound));
}

/// The same against the office example (goniometric luminaires, boxes, a
/// mesh): the exact sum's shadow tests against the sampled RIS estimate's.
#[test]
fn ris_direct_is_unbiased_in_the_office() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = lumest::scene::load(&root.join("data/office.toml")).unwrap();
    let pts: Vec<(DVec3, DVec3)> = std::fs::read_to_string(root.join("data/office_grid.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|s| s.parse().unwrap()).collect();
            (DVec3::new(v[0], v[1], v[2]), DVec3::new(v[3], v[4], v[5]))
        })
        .collect();
    let exact_scene = scene.clone().with_direct_lights(DirectLights::Exact, 8);
    let exact = Receivers::new(&exact_scene, &pts).unwrap();
    let ris_scene = scene.with_direct_lights(DirectLights::Ris, 8);
    let ris = Receivers::new(&ris_scene, &pts).unwrap();
    let est = sampled_direct(&ris_scene, &ris, 400, 5);
    let bound = sidak(pts.len());
    let zs: Vec<f64> = est
        .iter()
        .zip(exact.direct())
        .map(|(&(m, se), &e)| zcheck::z_score(m, se, e))
        .collect();
    let z1 = max_abs_z(zs.iter().copied());
    assert!(
        zcheck::within(z1, bound),
        "max |z| = {z1} > {bound}: {zs:?}"
    );
}

/// Total illuminance per point: exact part plus the estimated mean, and its
/// standard error.
fn totals(r: &lumest::run::RunResult) -> Vec<(f64, f64)> {
    (0..r.direct.len())
        .map(|j| {
            let w = &r.tallies.estimated[j];
            (r.direct[j] + w.mean(), w.std_error())
        })
        .collect()
}

/// Backward paths with next-event estimation from one RIS-kept source per
/// vertex (and the sampled RIS direct light) against the local estimator
/// with the exact sum at set-up (no shared code but the scene): the totals
/// agree (Sidak-corrected z over the points), and a 2 % error would not.
/// (Summed next-event estimation over the 200 sources is 32 times slower
/// per path here, too slow for a test.)
#[test]
fn ris_backward_agrees_with_exact_local() {
    const CHAINS: u64 = 200_000;
    const PATHS: u64 = 16_000;
    let scene = hall(0.7);
    let pts = hall_points();
    let exact_scene = scene.clone().with_direct_lights(DirectLights::Exact, 8);
    let rec = Receivers::new(&exact_scene, &pts).unwrap();
    let cfg = chains_cfg(CHAINS, 1, 0);
    let local = totals(&lumest::estimator::local::run(
        &exact_scene,
        &rec,
        &cfg,
        &mut |_| true,
    ));
    let ris_scene = scene.with_direct_lights(DirectLights::Ris, 8);
    let rec = Receivers::new(&ris_scene, &pts).unwrap();
    let cfg = chains_cfg(PATHS, 2, 0);
    let back = totals(&lumest::backward::run(&ris_scene, &rec, &cfg, &mut |_| {
        true
    }));
    let bound = sidak(pts.len());
    let z = |scale: f64| {
        max_abs_z(
            local
                .iter()
                .zip(&back)
                .map(|(&(a, sa), &(b, sb))| (scale * b - a) / (scale * sb).hypot(sa)),
        )
    };
    let z1 = z(1.0);
    assert!(zcheck::within(z1, bound), "max |z| = {z1} > {bound}");
    assert!(
        !zcheck::within(z(1.02), bound) && !zcheck::within(z(0.98), bound),
        "a 2 % error would pass: {} / {}",
        z(1.02),
        z(0.98)
    );
}

/// The local estimator with the light array (sampled direct light and the
/// near part's backward paths) gives the same numbers bit for bit on 1, 2
/// and 3 threads.
#[test]
fn ris_runs_are_bit_reproducible_for_any_thread_count() {
    let scene = hall(0.5).with_direct_lights(DirectLights::Ris, 8);
    let pts = hall_points();
    let rec = Receivers::new(&scene, &pts).unwrap();
    assert!(rec.has_sampled_direct());
    let bits = |threads: usize| {
        let r =
            lumest::estimator::local::run(&scene, &rec, &chains_cfg(6000, 3, threads), &mut |_| {
                true
            });
        totals(&r)
            .iter()
            .map(|&(m, s)| (m.to_bits(), s.to_bits()))
            .collect::<Vec<_>>()
    };
    let one = bits(1);
    assert_eq!(one, bits(2));
    assert_eq!(one, bits(3));
}
