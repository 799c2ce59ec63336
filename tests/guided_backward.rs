//! Backward paths with light-guided connections (multiple importance
//! sampling between the BRDF-sampled next vertex and photon first hits,
//! [`lumest::backward`]): unbiased against the exact Sobolev solution with
//! the source 1 cm above a plane, where plain next-event estimation has
//! rare huge scores; and the `sparse` check on the far field.

mod common;
use common::{chains_cfg, z, zcheck};
use glam::DVec3;
use lumest::cases::sobolev::sobolev_case;
use lumest::chain::ChainParams;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::RunConfig;
use lumest::tally::sidak_bound;

/// Points on the floor (plane 1, facing up) or the ceiling at height 1
/// (plane 2, facing down) at distance `r` along x.
fn plane_points(at: &[(u8, f64)]) -> Vec<(DVec3, DVec3)> {
    at.iter()
        .map(|&(plane, r)| {
            if plane == 1 {
                (DVec3::new(r, 0.0, 0.0), DVec3::Z)
            } else {
                (DVec3::new(r, 0.0, 1.0), -DVec3::Z)
            }
        })
        .collect()
}

fn guided(on: bool, paths: u64) -> RunConfig {
    RunConfig {
        chain: ChainParams {
            guide: on,
            ..ChainParams::default()
        },
        ..chains_cfg(paths, 3, 0)
    }
}

#[test]
fn guided_backward_paths_agree_with_the_exact_solution_next_to_the_source() {
    let (h1, rho) = (0.01, 0.9);
    let s = Sobolev::new(h1, 1.0 - h1, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    // Under the source, near it, on the far plane above it and further out.
    let at = [(1u8, 0.0), (1, 0.03), (1, 0.3), (2, 0.0), (2, 2.0)];
    let pts = plane_points(&at);
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let paths = 8192;
    let on = lumest::backward::run(&case.scene, &rec, &guided(true, paths), &mut |_| true);
    let off = lumest::backward::run(&case.scene, &rec, &guided(false, paths), &mut |_| true);
    let bound = sidak_bound(1e-3, at.len(), None);
    let mut var_ratio = Vec::new();
    for (j, &(plane, r)) in at.iter().enumerate() {
        let exact = s.illuminance(plane, r).e;
        let zj = z(&on, j, exact);
        let (se_on, se_off) = (
            on.tallies.estimated[j].std_error(),
            off.tallies.estimated[j].std_error(),
        );
        eprintln!(
            "plane {plane} r = {r}: exact {exact:.6}, guided z = {zj:.2} (se {se_on:.3e}), plain NEE se {se_off:.3e}"
        );
        assert!(
            zj.abs() < bound,
            "plane {plane} r = {r}: |z| = {zj:.2} > {bound:.2}"
        );
        var_ratio.push((se_off / se_on).powi(2));
    }
    // Same number of paths: the guided variance is far smaller where the
    // vertices come within centimetres of the source (measured: 37 to 330
    // times on these points; asked: 10).
    let worst = var_ratio.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        worst > 10.0,
        "variance ratios plain / guided: {var_ratio:?}"
    );
}

#[test]
fn sparse_check_flags_the_far_field_the_plain_estimate_misses() {
    // rho1 rho2 = 0.99: at r = 1e4 the plain local estimate is ~100 % low
    // with a steady error bar (the stress matrix); at r = 1 it is fine.
    let rho = 0.99f64.sqrt();
    let s = Sobolev::new(0.5, 0.5, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let pts = [
        (DVec3::new(1.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1e4, 0.0, 0.0), DVec3::Z),
    ];
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    // Facing a plane 1 m away: ten times the median probe distance.
    assert!((rec.view_radius(0) - 10.0 * 2f64.sqrt()).abs() < 2.0);
    let plain = RunConfig {
        near_auto: false,
        ..chains_cfg(16384, 1, 0)
    };
    let r = run(&case.scene, &rec, &plain, &mut |_| true);
    let near = r.tallies.diagnostics(0, r.direct[0]);
    let far = r.tallies.diagnostics(1, r.direct[1]);
    assert!(!near.flag().contains("sparse"), "r = 1: {}", near.flag());
    assert!(far.flag().contains("sparse"), "r = 1e4: {}", far.flag());
    // With the split covering the whole watched ball the check is off.
    let split = rec.clone().with_near_field(100.0, 1);
    assert!(!split.watched(1));
}

#[test]
fn recursive_near_part_recovers_the_far_field() {
    // rho1 rho2 = 0.99, r = 1e4: `--near-radius auto` joins the near
    // part's path vertices to the chains' collisions around the source.
    // (r = 100 m: see `far_field_at_100_m_is_precise_and_unflagged`.)
    let rho = 0.99f64.sqrt();
    let s = Sobolev::new(0.5, 0.5, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let at = [100.0, 1e4];
    let pts: Vec<(DVec3, DVec3)> = at
        .iter()
        .map(|&r| (DVec3::new(r, 0.0, 0.0), DVec3::Z))
        .collect();
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let cfg = RunConfig {
        near: (0.0, 16),
        near_auto: true,
        ..chains_cfg(8192, 2, 0)
    };
    let r = run(&case.scene, &rec, &cfg, &mut |_| true);
    let (j, x) = (1, 1e4);
    let exact = s.illuminance(1, x).e;
    let zj = z(&r, j, exact);
    let est = r.direct[j] + r.tallies.estimated[j].mean();
    let rel = r.tallies.estimated[j].std_error() / est;
    let flag = r.tallies.diagnostics(j, r.direct[j]).flag();
    eprintln!("r = {x}: {est:.6e} against {exact:.6e}, z = {zj:.2}, R = {rel:.2e}, {flag}");
    let bound = sidak_bound(1e-3, 1, Some(r.tallies.batches()));
    assert!(zj.abs() < bound, "r = {x}: |z| = {zj:.2} > {bound:.2}");
    // An error bar that means something (measured 0.45 %), and a tally
    // that passes every check.
    assert!(rel < 0.02, "r = {x}: R = {rel}");
    assert_eq!(flag, "ok", "r = {x}");
}

/// The near part at r = 100 m with a fixed radius (rho1 rho2 = 0.99): the
/// split radius `max(R, d / 2)` of every path vertex is at least `R`, so
/// with `R = 30` or `50 m` the light piled up around the source lies
/// within the path's reach from every vertex closer than about `R` to the
/// source and only paths that walk into the source's core (about 1 m, the
/// median distance from the source to the planes) bring its light
/// (measured with 8192 paths: 42 % of `E` comes from vertices within 10 m
/// of the source, 38 % from within 5 m). Runs without such a walk read
/// about half of `E` with a small, steady error bar (seed 2: 1.151e-3 lx,
/// R = 2.7 %, z = -37 at `R = 50 m`; z = -12.6 at 30 m). Not a bias: the
/// mean of 40 seeds is 2.18e-3 +- 0.15e-3 (z = -0.9). The near part's
/// reach count (`sparse`) must flag every run that disagrees with the
/// exact value; a run that is not flagged must agree with it.
#[test]
fn near_part_that_never_reaches_the_source_is_flagged() {
    let rho = 0.99f64.sqrt();
    let s = Sobolev::new(0.5, 0.5, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let rec = Receivers::new(&case.scene, &[(DVec3::new(100.0, 0.0, 0.0), DVec3::Z)]).unwrap();
    let exact = s.illuminance(1, 100.0).e;
    let runs = [(50.0, 2), (30.0, 2), (50.0, 38)];
    let mut wrong_and_unflagged = Vec::new();
    for (radius, seed) in runs {
        let cfg = RunConfig {
            near: (radius, 16),
            near_auto: false,
            ..chains_cfg(8192, seed, 0)
        };
        let r = run(&case.scene, &rec, &cfg, &mut |_| true);
        let d = r.tallies.diagnostics(0, r.direct[0]);
        let zj = z(&r, 0, exact);
        let flag = d.flag();
        eprintln!(
            "R = {radius} m, seed {seed}: z = {zj:.2}, R = {:.2e}, near reach {:?}, {flag}",
            d.rel_err, d.near_reach
        );
        eprintln!("  exposed, reached: {:?}", r.tallies.near_vertices[0]);
        let bound = sidak_bound(1e-3, runs.len(), Some(r.tallies.batches()));
        if flag == "ok" && (zj.is_nan() || zj.abs() >= bound) {
            wrong_and_unflagged.push(format!("R = {radius}, seed {seed}: z = {zj:.2}"));
        }
        // The near part's paths were exposed to the source's neighbourhood.
        assert!(d.near_reach.is_some(), "R = {radius}, seed {seed}");
    }
    assert!(wrong_and_unflagged.is_empty(), "{wrong_and_unflagged:#?}");
}

/// Known failure (issue 10, items 2 and 7). At r = 100 m in the same far
/// field (rho1 rho2 = 0.99, exact E = 2.3228e-3 lx) no configuration of the
/// local estimator reaches a trustworthy estimate in test time, and one is
/// silently wrong. Measured on one point, 8192 chains unless stated:
///
/// - `--near-radius auto` (R = 10 m), 16 paths: seeds 2-5 give R = 8.4 %
///   (ok, z -2.98), 33 % (R;VOV;tail), 7.4 % (ok), 12 % (R;VOV); 32768
///   chains: R = 8.5 % (VOV;tail): the error does not fall like 1/sqrt(N);
///   128 paths: R = 5.8 % in 14 s;
/// - plain, 65536 chains: R = 8.3 % (tail); backward, 4096 paths: R = 23-31 %;
/// - **fixed R = 50 m (d / 2), seed 2: 1.151e-3 lx, R = 2.7 %, flag `ok`,
///   z = -37** (half the light missing, every check passing); R = 30 m:
///   z = -12.6, `ok`; seed 3 at R = 50 m: 2.13e-3, R = 43 % (R;VOV;tail).
///   The same from the command line: data/sobolev.toml with both
///   reflectances 0.99498743710662, one point (100, 0, 0) facing up,
///   `--chains 8192 --near-radius 50 --near-paths 16 --seed 2` prints
///   E = 1.1513e-3 +- 3.1e-5, flag `ok`.
///
/// The split's heavy tail: the light at the point comes from rare paths
/// that link it with the region around the source; runs without such an
/// event are low and look converged. The near part's reach count now
/// flags all three runs `sparse` (none is silently wrong any more; see
/// `near_part_that_never_reaches_the_source_is_flagged`), but none is
/// precise and unflagged, which is what this test asks.
#[test]
#[ignore = "known failure, issue 10 items 2 and 7: far field at r = 100 m (see the doc comment)"]
fn far_field_at_100_m_is_precise_and_unflagged() {
    let rho = 0.99f64.sqrt();
    let s = Sobolev::new(0.5, 0.5, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let rec = Receivers::new(&case.scene, &[(DVec3::new(100.0, 0.0, 0.0), DVec3::Z)]).unwrap();
    let exact = s.illuminance(1, 100.0).e;
    let mut failures = Vec::new();
    for (name, near, seed) in [
        ("auto", (0.0, 16), 2),
        ("auto", (0.0, 16), 3),
        ("R = 50 m", (50.0, 16), 2),
    ] {
        let cfg = RunConfig {
            near,
            near_auto: near.0 == 0.0,
            ..chains_cfg(8192, seed, 0)
        };
        let r = run(&case.scene, &rec, &cfg, &mut |_| true);
        let est = r.direct[0] + r.tallies.estimated[0].mean();
        let rel = r.tallies.estimated[0].std_error() / est;
        let zj = z(&r, 0, exact);
        let flag = r.tallies.diagnostics(0, r.direct[0]).flag();
        let line = format!(
            "{name}, seed {seed}: {est:.4e} vs {exact:.4e}, z = {zj:.2}, R = {rel:.2e}, {flag}"
        );
        eprintln!("{line}");
        // Asked: a precise estimate (R < 5 %) that passes every check and
        // agrees with the exact value (Sidak over the three runs).
        let bound = sidak_bound(1e-3, 3, Some(r.tallies.batches()));
        if !(rel < 0.05 && flag == "ok" && zj.abs() < bound) {
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn recursive_near_part_keeps_reflection_orders_apart() {
    // Every point split (R = 0.3 m): orders 1, 2, 3 and the rest come from
    // the far part, the paths' NEE, their guided connections and their pool
    // connections together; each order must still match its Neumann term.
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 8, 2.0);
    let rec = Receivers::new(&case.scene, &case.points).unwrap();
    let cfg = RunConfig {
        orders: 3,
        near: (0.3, 8),
        ..chains_cfg(65_536, 6, 0)
    };
    let r = run(&case.scene, &rec, &cfg, &mut |_| true);
    assert!(rec.clone().with_near_field(0.3, 8).near_field().0 > 0);
    let mut worst: f64 = 0.0;
    for j in 0..case.points.len() {
        for k in 0..3 {
            let w = &r.tallies.orders[k][j];
            let exact = s.order(case.plane[j], case.r[j], k as u32 + 1);
            worst = zcheck::max_abs(worst, zcheck::z_score(w.mean(), w.std_error(), exact));
        }
    }
    let bound = sidak_bound(1e-3, 3 * case.points.len(), Some(r.tallies.batches()));
    eprintln!("orders with the recursive split: max |z| = {worst:.2} (bound {bound:.2})");
    assert!(worst < bound, "max |z| = {worst} exceeds {bound}");
}

#[test]
fn backward_sparse_check_flags_paths_that_never_reach_the_light() {
    // The same far field for the backward estimator: paths from r = 1e4
    // wander ~1e2 m between the planes and never come near the source, so
    // the estimate misses the halo around it (44 % low at rho1 rho2 =
    // 0.999 in the stress matrix). The `sparse` check counts path vertices
    // within the light's neighbourhood and must flag that point, and only it.
    let rho = 0.99f64.sqrt();
    let s = Sobolev::new(0.5, 0.5, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let pts = [
        (DVec3::new(1.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1e4, 0.0, 0.0), DVec3::Z),
    ];
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let light = &case.scene.lights[0];
    // Between two planes 0.5 m above and below: ten times the median probe distance.
    let reach = lumest::backward::light_reach(&case.scene, light);
    assert!(reach > 5.0 && reach < 30.0, "reach {reach}");
    let r = lumest::backward::run(&case.scene, &rec, &chains_cfg(1024, 3, 0), &mut |_| true);
    let near = r.tallies.diagnostics(0, r.direct[0]);
    let far = r.tallies.diagnostics(1, r.direct[1]);
    assert!(!near.flag().contains("sparse"), "r = 1: {}", near.flag());
    assert!(far.flag().contains("sparse"), "r = 1e4: {}", far.flag());
    // The near point is right (and its check honest): z against the exact value.
    let exact = s.illuminance(1, 1.0).e;
    let zj = z(&r, 0, exact);
    assert!(zj.abs() < sidak_bound(1e-3, 1, None), "r = 1: z = {zj}");
}

/// The same next to the source with an area light elsewhere in the scene
/// (a 1e-6 lm disc 50 m away, whose light is negligible here): the point
/// source stays guided (an area source gives no photons and is left out of
/// their density, as lights at infinity are). The old build turned
/// guidance off for every light as soon as one area source or luminous
/// opening was in the scene: plain next-event paths here covered 55-80 %
/// of runs, some flagged `ok` at z = -29 (a reviewer's measure).
#[test]
fn an_area_light_elsewhere_leaves_the_point_source_guided() {
    let (h1, rho) = (0.01, 0.9);
    let s = Sobolev::new(h1, 1.0 - h1, rho, rho, 1.0).unwrap();
    let src = "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
               material = { type = \"lambertian\", reflectance = 0.9 }\n\
               [[surface]]\ntype = \"plane\"\npoint = [0, 0, 1]\nnormal = [0, 0, -1]\n\
               material = { type = \"lambertian\", reflectance = 0.9 }\n\
               [[light]]\ntype = \"point\"\nposition = [0, 0, 0.01]\nintensity = 1\n\
               [[light]]\ntype = \"disc\"\ncenter = [50, 0, 0.999]\nnormal = [0, 0, -1]\n\
               radius = 0.01\nflux = 1e-6\n";
    let scene = lumest::scene::parse(src, std::path::Path::new("s9.toml")).unwrap();
    let at = [(1u8, 0.0), (1, 0.3), (1, 1.0), (2, 0.0), (2, 1.0)];
    let pts = plane_points(&at);
    let rec = Receivers::new(&scene, &pts).unwrap();
    let paths = 32768;
    let on = lumest::backward::run(&scene, &rec, &guided(true, paths), &mut |_| true);
    let off = lumest::backward::run(&scene, &rec, &guided(false, paths), &mut |_| true);
    let bound = sidak_bound(1e-3, at.len(), None);
    let mut var_ratio = Vec::new();
    for (j, &(plane, r)) in at.iter().enumerate() {
        let exact = s.illuminance(plane, r).e;
        let zj = z(&on, j, exact);
        assert!(
            zj.abs() < bound,
            "plane {plane} r = {r}: |z| = {zj:.2} > {bound:.2}"
        );
        let se = on.tallies.estimated[j].std_error();
        assert!(
            0.02 * exact > bound * se,
            "plane {plane} r = {r}: {se} too wide for 2 %"
        );
        let (se_on, se_off) = (
            on.tallies.estimated[j].std_error(),
            off.tallies.estimated[j].std_error(),
        );
        var_ratio.push((se_off / se_on).powi(2));
    }
    let worst = var_ratio.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        worst > 10.0,
        "variance ratios plain / guided: {var_ratio:?}"
    );
}
