//! Area sources (rectangles, discs) and sphere lights in rooms: the sampled
//! direct light (every MIS strategy) against brute-force quadrature that
//! shares no code with the estimators, partial occlusion, a source set into
//! a ceiling, what a view sees, both estimators, and the flux balance.

mod common;

use glam::DVec3;
use lumest::estimator::direct::{self, Strategy};
use lumest::estimator::{Receiver, Receivers};
use lumest::run::{RunConfig, Stop};
use lumest::sampling::Philox4x32;
use lumest::sampling::warp::Frame;
use lumest::scene::{Scene, parse};
use statrs::distribution::{ContinuousCDF, Normal};
use std::path::Path;

/// Two-sided z bound for `m` tests at family-wise false-alarm rate 1e-4 (Sidak).
fn sidak(m: usize) -> f64 {
    let a = 1.0 - (1.0 - 1e-4f64).powf(1.0 / m as f64);
    Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - a / 2.0)
}

fn scene(src: &str) -> Scene {
    parse(src, Path::new("test.toml")).unwrap()
}

const FLOOR: &str = r#"
[[surface]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = { type = "lambertian", reflectance = 0.5 }
"#;

const CEILING: &str = r#"
[[surface]]
name = "ceiling"
type = "plane"
point = [0.0, 0.0, 3.0]
normal = [0.0, 0.0, -1.0]
material = { type = "lambertian", reflectance = 0.5 }
"#;

/// The panel: 0.6 m x 1.2 m, 1000 cd/m^2, emitting down from z = `z`.
fn panel(z: f64) -> String {
    format!(
        r#"
[[light]]
type = "rectangle"
corner = [-0.3, 0.6, {z}]
edge1 = [0.6, 0.0, 0.0]
edge2 = [0.0, -1.2, 0.0]
luminance = 1000.0
"#
    )
}

/// A box that hides the panel from part of the floor: x in [0.2, 1.2],
/// y in [-1, 1], z in [1.0, 1.1].
const BLOCKER: &str = r#"
[[surface]]
name = "blocker"
type = "box"
min = [0.2, -1.0, 1.0]
max = [1.2, 1.0, 1.1]
material = { type = "lambertian", reflectance = 0.0 }
"#;

/// A box far from everything (it only makes the scene need sampling).
const FAR_BOX: &str = r#"
[[surface]]
name = "far"
type = "box"
min = [50.0, 50.0, 0.5]
max = [51.0, 51.0, 1.0]
material = { type = "lambertian", reflectance = 0.5 }
"#;

/// Whether the segment from `x` to `y` crosses the blocker box (slab test,
/// written here independently of the library's shapes).
fn blocked(x: DVec3, y: DVec3) -> bool {
    let (lo, hi) = (DVec3::new(0.2, -1.0, 1.0), DVec3::new(1.2, 1.0, 1.1));
    let d = y - x;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k].abs() < 1e-300 {
            if x[k] < lo[k] || x[k] > hi[k] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[k] - x[k]) / d[k], (hi[k] - x[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    t0 < t1
}

/// Direct illuminance \[lx\] at `x` (normal `n`) from the panel at height
/// `z` (emitting down, 1000 cd/m^2), by an `m x 2m` midpoint rule over its
/// area, with the blocker if `block`.
fn panel_brute(x: DVec3, n: DVec3, z: f64, block: bool, m: usize) -> f64 {
    let (dx, dy) = (0.6 / m as f64, 1.2 / (2 * m) as f64);
    let mut sum = 0.0;
    for i in 0..m {
        for k in 0..2 * m {
            let y = DVec3::new(
                -0.3 + (i as f64 + 0.5) * dx,
                -0.6 + (k as f64 + 0.5) * dy,
                z,
            );
            let v = y - x;
            let d2 = v.length_squared();
            let cx = n.dot(v) / d2.sqrt();
            let cy = v.z / d2.sqrt(); // the panel faces -z: cos_y = (x - y).(-z)/d
            if cx <= 0.0 || cy <= 0.0 || (block && blocked(x, y)) {
                continue;
            }
            sum += cx * cy / d2;
        }
    }
    1000.0 * sum * dx * dy
}

/// Mean and standard error of `n` direct-light samples at receiver `j`.
fn sample_mean(
    s: &Scene,
    rec: &Receivers,
    j: usize,
    strategy: Strategy,
    n: u64,
    seed: u64,
) -> (f64, f64) {
    let set = rec.direct_set(j).expect("sampled here");
    let r = &rec.receivers()[j];
    let frame = Frame::from_normal(r.n);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for i in 0..n {
        let mut rng = Philox4x32::new(seed, i);
        let v = direct::sample(s, set, r, &frame, strategy, None, &mut rng);
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    (mean, (var / n as f64).sqrt())
}

#[test]
fn sampled_direct_light_is_unbiased_for_every_strategy_with_and_without_occlusion() {
    let points = [
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1.0, 0.3, 0.0), DVec3::Z), // under the blocker: wholly hidden
        (DVec3::new(1.6, 0.0, 0.5), DVec3::Z), // beside it: partly hidden
        (DVec3::new(2.0, -0.5, 1.5), DVec3::new(-0.6, 0.0, 0.8)),
        (DVec3::new(0.0, 0.0, 2.9), DVec3::Z), // close below the panel
    ];
    let strategies = [
        Strategy::Light,
        Strategy::Brdf,
        Strategy::Balance,
        Strategy::Power,
    ];
    let bound = sidak(2 * points.len() * strategies.len());
    for (block, extra) in [(false, FAR_BOX), (true, BLOCKER)] {
        let s = scene(&format!("{FLOOR}{extra}{}", panel(3.0)));
        let rec = Receivers::new(&s, &points).unwrap();
        for (j, &(x, n)) in points.iter().enumerate() {
            // Nothing of the panel is exact here: the boxes make it sampled.
            assert_eq!(rec.direct()[j], 0.0);
            let exact = panel_brute(x, n, 3.0, block, 600);
            for st in strategies {
                let (m, se) = sample_mean(&s, &rec, j, st, 40_000, 7 + j as u64);
                if exact == 0.0 {
                    assert_eq!(m, 0.0, "block {block} point {j} {st:?}: wholly hidden");
                    continue;
                }
                let z = (m - exact) / se;
                assert!(
                    z.abs() < bound,
                    "block {block} point {j} {st:?}: {m} +- {se} vs {exact} (z = {z:.2})"
                );
                // A reference 2 % off is rejected (the test can fail).
                assert!(
                    st != Strategy::Balance || ((m - 1.02 * exact) / se).abs() > bound,
                    "point {j} {st:?}: too imprecise to tell 2 %"
                );
            }
        }
    }
}

#[test]
fn mis_beats_brdf_sampling_close_to_the_panel_and_light_sampling_on_a_glossy_receiver() {
    // Close below the panel BRDF (cosine) sampling wastes most directions;
    // MIS stays near the better strategy.
    let s = scene(&format!("{FLOOR}{FAR_BOX}{}", panel(3.0)));
    let x = DVec3::new(3.0, 0.0, 0.0);
    let rec = Receivers::new(&s, &[(x, DVec3::Z)]).unwrap();
    let var = |st| {
        let (_, se) = sample_mean(&s, &rec, 0, st, 20_000, 3);
        se * se * 20_000.0
    };
    let (vl, vb, vm) = (
        var(Strategy::Light),
        var(Strategy::Brdf),
        var(Strategy::Balance),
    );
    assert!(vm < 2.0 * vl.min(vb), "MIS {vm} vs light {vl}, BRDF {vb}");
    assert!(
        vl < vb,
        "a small panel far off: light sampling wins ({vl} vs {vb})"
    );
}

#[test]
fn a_panel_set_into_the_ceiling_plane_equals_one_just_below_it() {
    // The light lies exactly in the ceiling's plane (the common case), or
    // 1e-7 m below: the answers agree, and a view looking up sees 1000 cd/m^2.
    let points = [
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1.5, 0.5, 0.8), DVec3::Z),
        (DVec3::new(0.1, 0.1, 2.5), DVec3::new(0.0, 0.0, -1.0)), // faces the ceiling
    ];
    let cfg = common::chains_cfg(400_000, 11, 2);
    let mut res = Vec::new();
    for z in [3.0, 3.0 - 1e-7] {
        let s = scene(&format!("{FLOOR}{CEILING}{FAR_BOX}{}", panel(z)));
        let rec = Receivers::new(&s, &points).unwrap();
        let r = lumest::estimator::local::run(&s, &rec, &cfg, &mut |_| true);
        res.push(r);
        let lum = lumest::estimator::emitted_luminance(
            &s,
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::Z,
            f64::INFINITY,
        );
        assert_eq!(lum, 1000.0, "z = {z}: a view up into the panel");
        let beside = lumest::estimator::emitted_luminance(
            &s,
            DVec3::new(2.0, 0.0, 1.0),
            DVec3::Z,
            f64::INFINITY,
        );
        assert_eq!(beside, 0.0);
    }
    let bound = sidak(points.len());
    for j in 0..points.len() {
        let e = |k: usize| res[k].direct[j] + res[k].tallies.estimated[j].mean();
        let se = (res[0].tallies.estimated[j].std_error().powi(2)
            + res[1].tallies.estimated[j].std_error().powi(2))
        .sqrt();
        let z = (e(0) - e(1)) / se;
        assert!(
            z.abs() < bound,
            "point {j}: {} vs {} (z = {z:.2})",
            e(0),
            e(1)
        );
        assert!(e(0) > 0.0);
    }
    // The floor point's direct part against quadrature (plus light reflected
    // by the ceiling, which the chains give): direct alone is checked by its
    // sampled mean.
    let d = res[0].tallies.sampled_direct_mean(0);
    let sd = res[0].tallies.sampled_direct[0].std_error();
    let exact = panel_brute(points[0].0, points[0].1, 3.0, false, 600);
    assert!(
        ((d - exact) / sd).abs() < sidak(1),
        "{d} +- {sd} vs {exact}"
    );
}

#[test]
fn both_estimators_agree_on_a_room_lit_by_a_panel_and_a_sphere() {
    let src = format!(
        "{FLOOR}{CEILING}{BLOCKER}{}{}",
        panel(3.0),
        r#"
[[light]]
type = "sphere"
center = [1.5, 1.5, 2.0]
radius = 0.2
flux = 2000.0
"#
    );
    let s = scene(&src);
    let points = [
        (DVec3::new(0.7, 0.0, 0.5), DVec3::Z),
        (DVec3::new(2.0, 2.0, 0.0), DVec3::Z),
        (DVec3::new(0.0, 0.0, 2.0), DVec3::new(1.0, 0.0, 0.0)),
    ];
    let rec = Receivers::new(&s, &points).unwrap();
    let cfg = common::chains_cfg(200_000, 5, 2);
    let a = lumest::estimator::local::run(&s, &rec, &cfg, &mut |_| true);
    let cfg_b = RunConfig {
        stop: Stop {
            chains: Some(6_000),
            ..Stop::default()
        },
        ..cfg.clone()
    };
    let b = lumest::backward::run(&s, &rec, &cfg_b, &mut |_| true);
    let bound = sidak(points.len());
    for j in 0..points.len() {
        let (ea, eb, se) = common::apart(&a, &b, j);
        assert!(
            ((ea - eb) / se).abs() < bound,
            "point {j}: local {ea} vs backward {eb} +- {se}"
        );
    }
}

#[test]
fn a_partly_hidden_sphere_light_in_a_room_against_quadrature() {
    // The sphere sits just above the blocker's edge: points below see part of it.
    let src = format!(
        "{FLOOR}{BLOCKER}{}",
        r#"
[[light]]
type = "sphere"
center = [1.2, 0.0, 1.6]
radius = 0.25
intensity = 100.0
"#
    );
    let s = scene(&src);
    let (c, r) = (DVec3::new(1.2, 0.0, 1.6), 0.25);
    let lum = 100.0 / (std::f64::consts::PI * r * r);
    // Brute force over the sphere's visible surface: E = int L cos_x cos_y / d^2 dA
    // over the part of the sphere facing x, with the blocker's shadow.
    let brute = |x: DVec3, n: DVec3| {
        let m = 600;
        let mut sum = 0.0;
        for i in 0..m {
            let ct = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
            let st = (1.0 - ct * ct).sqrt();
            for k in 0..2 * m {
                let ph = std::f64::consts::PI * (k as f64 + 0.5) / m as f64;
                let q = DVec3::new(st * ph.cos(), st * ph.sin(), ct);
                let y = c + q * r;
                let v = y - x;
                let d2 = v.length_squared();
                let (cx, cy) = (n.dot(v) / d2.sqrt(), -q.dot(v) / d2.sqrt());
                if cx > 0.0 && cy > 0.0 && !blocked(x, y) {
                    sum += cx * cy / d2;
                }
            }
        }
        lum * sum * r * r * (2.0 / m as f64) * (std::f64::consts::PI / m as f64)
    };
    let points = [
        (DVec3::new(0.9, 0.0, 0.0), DVec3::Z), // under the blocker: partly hidden
        (DVec3::new(1.6, 0.3, 0.0), DVec3::Z),
        (DVec3::new(0.0, 0.0, 1.5), DVec3::X), // sees all of it
    ];
    let rec = Receivers::new(&s, &points).unwrap();
    let bound = sidak(points.len());
    // Wholly hidden under the blocker: exactly nothing.
    let hidden = Receivers::new(&s, &[(DVec3::new(0.7, 0.0, 0.6), DVec3::Z)]).unwrap();
    assert_eq!(
        sample_mean(&s, &hidden, 0, Strategy::Balance, 1000, 1),
        (0.0, 0.0)
    );
    for (j, &(x, n)) in points.iter().enumerate() {
        let exact = brute(x, n);
        let (m, se) = sample_mean(&s, &rec, j, Strategy::Balance, 100_000, 9);
        assert!(
            ((m - exact) / se).abs() < bound,
            "point {j}: {m} +- {se} vs {exact}"
        );
        assert!(exact > 0.0);
    }
}

#[test]
fn a_view_receiver_on_a_glossy_floor_gets_its_direct_light_sampled() {
    let src = format!(
        "{}{CEILING}{}",
        r#"
[[surface]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = { type = "phong", diffuse = 0.2, specular = 0.5, exponent = 50 }
"#,
        panel(3.0)
    );
    let s = scene(&src);
    // Luminance at a floor point seen from where the panel's mirror image lies.
    let sub = DVec3::new(1.0, 0.0, 0.0);
    let wo_world = (DVec3::new(2.0, 0.0, 3.0) - sub).normalize();
    let frame = Frame::from_normal(DVec3::Z);
    let material = s.surfaces[0].material;
    let r = Receiver {
        p: sub,
        n: DVec3::Z,
        response: lumest::estimator::Response::Luminance {
            material,
            wo: frame.to_local(wo_world),
        },
    };
    let rec = Receivers::from_receivers(&s, &[r]).unwrap();
    assert_eq!(rec.direct()[0], 0.0, "a glossy response is sampled");
    // Reference: L = int L_e f(wi, wo) cos dw by quadrature over the panel.
    let m = 600;
    let (dx, dy) = (0.6 / m as f64, 1.2 / (2 * m) as f64);
    let mut exact = 0.0;
    for i in 0..m {
        for k in 0..2 * m {
            let y = DVec3::new(
                -0.3 + (i as f64 + 0.5) * dx,
                -0.6 + (k as f64 + 0.5) * dy,
                3.0,
            );
            let v = y - sub;
            let d2 = v.length_squared();
            let wi = v / d2.sqrt();
            let f = material.eval(frame.to_local(wi), frame.to_local(wo_world));
            exact += 1000.0 * f * wi.z * wi.z / d2 * dx * dy;
        }
    }
    let mut vars = Vec::new();
    for st in [Strategy::Light, Strategy::Brdf, Strategy::Balance] {
        let (mean, se) = sample_mean(&s, &rec, 0, st, 100_000, 21);
        assert!(
            ((mean - exact) / se).abs() < sidak(3),
            "{st:?}: {mean} +- {se} vs {exact}"
        );
        vars.push(se);
    }
    assert!(
        vars[2] < vars[0].max(vars[1]),
        "MIS no worse than the worse strategy: {vars:?}"
    );
}

#[test]
fn black_box_absorbs_exactly_the_power_of_every_light_kind() {
    // A closed black box: every emitted lumen is absorbed at the first hit.
    let walls = r#"
[[surface]]
name = "room"
type = "box"
min = [0.0, 0.0, 0.0]
max = [4.0, 3.0, 3.0]
normals = "inward"
material = { type = "lambertian", reflectance = 0.0 }
"#;
    let lights = [
        panel(3.0).replace("[-0.3, 0.6,", "[1.0, 1.6,"),
        r#"
[[light]]
type = "disc"
center = [2.0, 1.5, 1.0]
normal = [0.3, 0.0, 1.0]
radius = 0.3
flux = 500.0
sides = "both"
"#
        .to_string(),
        r#"
[[light]]
type = "sphere"
center = [2.0, 1.5, 1.5]
radius = 0.4
flux = 700.0
"#
        .to_string(),
    ];
    for l in &lights {
        let src = format!("{walls}{l}");
        let s = match parse(&src, Path::new("box.toml")) {
            Ok(s) => s,
            Err(e) => panic!("{e}\n{src}"),
        };
        let f = lumest::cases::flux_balance::flux_balance(&s, 64_000, 32, 3);
        assert_eq!(f.escaped, 0, "{l}");
        let z =
            (f.total.mean() - s.total_power()) / f.total.std_error().max(1e-12 * s.total_power());
        assert!(
            z.abs() < 4.0,
            "{l}: absorbed {} vs {}",
            f.total.mean(),
            s.total_power()
        );
    }
}

#[test]
fn a_cosine_luminaire_emitting_from_its_opening_is_the_lambertian_panel() {
    // An IES table I = I0 cos(gamma) with a 0.6 m (C0, x) by 1.2 m (C90, y)
    // opening: every element of the opening then emits like a Lambertian
    // surface of luminance I0 / A, so the luminaire is the panel of the
    // other tests (I0 = 1000 cd/m^2 x 0.72 m^2). Near it the point
    // approximation is off; the opening agrees with the panel's quadrature.
    let dir = std::env::temp_dir().join(format!("lumest-opening-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let gammas: Vec<f64> = (0..=180).map(|k| k as f64 * 0.5).collect();
    let cd: Vec<String> = gammas
        .iter()
        .map(|g: &f64| format!("{:.17e}", 720.0 * g.to_radians().cos()))
        .collect();
    let ies = format!(
        "IESNA:LM-63-2002\n[TEST] cosine panel\nTILT=NONE\n1 -1 1 {} 1 1 2 1.2 0.6 0\n1 1 0\n{}\n0\n{}\n",
        gammas.len(),
        gammas
            .iter()
            .map(|g| g.to_string())
            .collect::<Vec<_>>()
            .join(" "),
        cd.join(" ")
    );
    std::fs::write(dir.join("panel.ies"), ies).unwrap();
    let with = |opening: bool| {
        let src = format!(
            "{FLOOR}{FAR_BOX}\n[[light]]\ntype = \"ies\"\nfile = \"panel.ies\"\nposition = [0.0, 0.0, 3.0]\nopening = {opening}\n"
        );
        parse(&src, &dir.join("scene.toml")).unwrap()
    };
    let (s_open, s_point) = (with(true), with(false));
    let points = [
        (DVec3::new(0.0, 0.0, 2.5), DVec3::Z),
        (DVec3::new(0.5, 0.2, 2.7), DVec3::Z),
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1.0, -0.4, 2.0), DVec3::new(-1.0, 0.0, 0.0)),
    ];
    let rec_open = Receivers::new(&s_open, &points).unwrap();
    let rec_point = Receivers::new(&s_point, &points).unwrap();
    let bound = sidak(points.len());
    for (j, &(x, n)) in points.iter().enumerate() {
        let exact = panel_brute(x, n, 3.0, false, 600);
        assert_eq!(rec_open.direct()[j], 0.0, "the opening's light is sampled");
        let (m, se) = sample_mean(&s_open, &rec_open, j, Strategy::Balance, 100_000, 13);
        let z = (m - exact) / se;
        assert!(
            z.abs() < bound,
            "point {j}: opening {m} +- {se} vs panel {exact} (z = {z:.2})"
        );
        let point = rec_point.direct()[j];
        if j < 2 {
            // Half a metre or less from a 1.3 m opening: the point is far off.
            assert!(
                ((point - exact) / exact).abs() > 0.05,
                "point {j}: {point} vs {exact}"
            );
            assert!(((m - point) / se).abs() > bound);
        }
    }
    // The chains: light reflected by the floor into points facing down is
    // the same from the opening as from the panel (emission sampled by
    // position and direction; nothing else differs below the panel).
    let down = [
        (DVec3::new(0.0, 0.0, 1.0), -DVec3::Z),
        (DVec3::new(1.5, 0.5, 2.0), -DVec3::Z),
    ];
    let panel = scene(&format!("{FLOOR}{FAR_BOX}{}", panel(3.0)));
    let cfg = common::chains_cfg(100_000, 17, 2);
    let a = lumest::estimator::local::run(
        &s_open,
        &Receivers::new(&s_open, &down).unwrap(),
        &cfg,
        &mut |_| true,
    );
    let b = lumest::estimator::local::run(
        &panel,
        &Receivers::new(&panel, &down).unwrap(),
        &cfg,
        &mut |_| true,
    );
    for j in 0..down.len() {
        // (Both lights sit behind these points: no exact direct part.)
        let (ea, eb, se) = common::apart(&a, &b, j);
        assert!(
            ea > 0.0 && ((ea - eb) / se).abs() < sidak(down.len()),
            "point {j}: opening {ea} vs panel {eb} +- {se}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn lights_alone_and_panels_in_a_plane_get_the_exact_direct_light() {
    // A scene of the panel alone, and the panel set into the ceiling plane
    // of two planes: nothing can hide it, so its direct light is exact (no
    // sampling), and it equals the quadrature.
    let points = [
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1.0, 0.3, 0.0), DVec3::Z),
        (DVec3::new(2.0, -0.5, 1.5), DVec3::new(-0.6, 0.0, 0.8)),
        (DVec3::new(0.0, 0.0, 2.9), DVec3::Z),
        (DVec3::new(0.0, 0.0, 2.0), DVec3::new(1.0, 0.0, 0.0)), // edge-on: half the panel
        (DVec3::new(0.5, 0.2, 3.5), -DVec3::Z),                 // behind it: nothing
    ];
    for src in [panel(3.0), format!("{FLOOR}{CEILING}{}", panel(3.0))] {
        let s = scene(&src);
        let rec = Receivers::new(&s, &points).unwrap();
        assert!(!rec.has_sampled_direct(), "{src}");
        for (j, &(x, n)) in points.iter().enumerate() {
            let exact = if x.z > 3.0 {
                0.0
            } else {
                panel_brute(x, n, 3.0, false, 1200)
            };
            let got = rec.direct()[j];
            assert!(
                (got - exact).abs() <= 1e-5 * exact.abs().max(1e-3),
                "point {j}: {got} vs {exact}"
            );
        }
        if !src.contains("floor") {
            // Nothing reflects: the estimate is the exact part, with zero error.
            let r = lumest::estimator::local::run(
                &s,
                &rec,
                &common::chains_cfg(10_000, 1, 2),
                &mut |_| true,
            );
            for j in 0..points.len() {
                assert_eq!(r.tallies.estimated[j].mean(), 0.0);
            }
        }
    }
}

/// A uniform disc alone is exact however its normal rounds: `[0, 1, 1]`
/// normalises to a vector an ulp short of unit length, and the disc's
/// reach out of its own plane, `R sqrt(1 - (n . n)^2)`, came to 1.5e-8 m,
/// past the tolerance: its direct light was sampled (1559.28 +- 7.02 lx
/// against 1561.3603 exactly, a reviewer's find). On the axis, facing it
/// at distance h: `pi L R^2 / (h^2 + R^2)`.
#[test]
fn a_tilted_uniform_disc_alone_is_exact() {
    for normal in [[0.0, 1.0, 1.0], [0.3, -0.5, 0.8], [0.6, 0.0, 0.8]] {
        let s = scene(&format!(
            "[[light]]\ntype = \"disc\"\ncenter = [0.1, 0.2, 0.3]\nnormal = [{}, {}, {}]\nradius = 0.7\nluminance = 500.0\n",
            normal[0], normal[1], normal[2]
        ));
        let n = DVec3::from_array(normal).normalize();
        let points: Vec<_> = [0.05, 0.5, 2.0]
            .iter()
            .map(|&h| (DVec3::new(0.1, 0.2, 0.3) + h * n, -n))
            .collect();
        let rec = Receivers::new(&s, &points).unwrap();
        assert!(!rec.has_sampled_direct(), "normal {normal:?}");
        for (j, h) in [0.05f64, 0.5, 2.0].into_iter().enumerate() {
            let exact = std::f64::consts::PI * 500.0 * 0.49 / (h * h + 0.49);
            let got = rec.direct()[j];
            assert!(
                (got - exact).abs() <= 1e-9 * exact,
                "{normal:?} h {h}: {got} vs {exact}"
            );
        }
    }
}

#[test]
fn disc_sources_with_every_radial_profile_against_quadrature() {
    use lumest::cases::luminaires::{DISC_PROFILES, disc_case};
    let dir = std::env::temp_dir().join(format!("lumest-discs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cfg = common::chains_cfg(60_000, 4, 2);
    let cases: Vec<_> = (0..DISC_PROFILES.len())
        .map(|k| disc_case(&dir, k).unwrap())
        .collect();
    let bound = sidak(cases.iter().map(|c| c.exact.len()).sum());
    for (k, case) in cases.iter().enumerate() {
        let rec = Receivers::from_receivers(&case.scene, &case.receivers).unwrap();
        assert!(rec.has_sampled_direct());
        let r = lumest::estimator::local::run(&case.scene, &rec, &cfg, &mut |_| true);
        let mut resolved = false;
        for (j, &e) in case.exact.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let est = r.direct[j] + w.mean();
            let z = (est - e) / w.std_error();
            assert!(
                z.abs() < bound,
                "profile {k} point {j}: {est} +- {} vs {e} (z = {z:.2})",
                w.std_error()
            );
            resolved |= ((est - 1.02 * e) / w.std_error()).abs() > bound;
        }
        assert!(resolved, "profile {k}: no point resolves a 2 % error");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Where nothing reflects, the reflected part is exactly 0 and the
/// `sparse` check (too few collisions near the point to trust its
/// reflected light) has nothing to judge, though the sampled direct light
/// of an area source is an estimate with an error bar: a disc with a
/// radial profile and no surface at all, and a panel in a black box, flag
/// no point `sparse` (both did, with the sampled direct light taken for
/// reflected light).
#[test]
fn direct_light_alone_is_never_sparse() {
    let dir = tempfile::tempdir().unwrap();
    let disc = "[[light]]\ntype = \"disc\"\ncenter = [0, 0, 3]\nnormal = [0, 0, -1]\n\
                radius = 0.4\nflux = 1000.0\nprofile = \"linear-decreasing\"\n";
    let boxed = "[[surface]]\ntype = \"box\"\nmin = [-2, -2, 0]\nmax = [2, 2, 3]\n\
                 material = { type = \"lambertian\", reflectance = 0 }\n\n\
                 [[light]]\ntype = \"rectangle\"\ncorner = [-0.3, -0.3, 2.99]\n\
                 edge1 = [0, 0.6, 0]\nedge2 = [0.6, 0, 0]\nflux = 1000.0\n";
    let mut points = String::from("id,x,y,z,nx,ny,nz\na,0,0,2.9,0,0,1\nb,0.5,0,1,0,0,1\n");
    for k in 0..24 {
        let z = 0.1 + 0.12 * f64::from(k);
        points += &format!("w{k},1.999,0.{k},{z},-1,0,0\n");
    }
    std::fs::write(dir.path().join("p.csv"), &points).unwrap();
    for (name, src) in [("disc", disc), ("boxed", boxed)] {
        let s = dir.path().join(format!("{name}.toml"));
        std::fs::write(&s, src).unwrap();
        let o = dir.path().join(format!("{name}.csv"));
        let out = assert_cmd::Command::cargo_bin("lumest")
            .unwrap()
            .args([
                "illuminance",
                "--quiet",
                "--chains",
                "100000",
                "--seed",
                "1",
            ])
            .arg("--scene")
            .arg(&s)
            .arg("--points")
            .arg(dir.path().join("p.csv"))
            .arg("--out")
            .arg(&o)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = std::fs::read_to_string(&o).unwrap();
        let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let (e, f) = (
            head.iter().position(|h| *h == "E_stderr").unwrap(),
            head.iter().position(|h| *h == "E_flag").unwrap(),
        );
        for line in text.lines().skip(1) {
            let c: Vec<&str> = line.split(',').collect();
            let se: f64 = c[e].parse().unwrap();
            assert!(se > 0.0, "{name}: the direct light is sampled: {line}");
            assert!(!c[f].contains("sparse"), "{name}: {line}");
        }
    }
}

/// A disc whose luminance vanishes on a ring (`v` profile, turning radius
/// 0.1 m of 0.4 m, peak 500 cd/m^2) 3 m above a point: the sampled direct
/// light under the default MIS (power heuristic) against a 1-D quadrature
/// of `L(s) h^2 / (h^2 + s^2)^2 2 pi s` that shares no code with the
/// sampler, and its samples' spread. Weighed by the sampling density, which
/// vanishes on the ring, the rare cosine samples that hit near the ring
/// took the weight there: 1.8 times the standard deviation of light
/// sampling alone and a kurtosis of 690, enough to flag batch means `VOV`
/// or `tail` in half the runs. With weights from a density mixed with the
/// uniform one the spread is light sampling's.
#[test]
fn a_ring_of_zero_luminance_keeps_light_sampling_s_spread() {
    let sc = scene(
        "[[light]]\ntype = \"disc\"\ncenter = [0, 0, 3]\nnormal = [0, 0, -1]\nradius = 0.4\n\
         luminance = 500.0\nprofile = { type = \"v\", turning = 0.1 }\n",
    );
    let (h, r, t, peak) = (3.0f64, 0.4f64, 0.1f64, 500.0f64);
    let g = |s: f64| (s - t).abs() / t.max(r - t);
    // Midpoint rule on [0, t] and [t, r] (the kink at t), 20,000 cells each.
    let mut exact = 0.0;
    for (a, b) in [(0.0, t), (t, r)] {
        let m = 20_000;
        let ds = (b - a) / m as f64;
        for k in 0..m {
            let s = a + (k as f64 + 0.5) * ds;
            exact +=
                peak * g(s) * h * h / (h * h + s * s).powi(2) * 2.0 * std::f64::consts::PI * s * ds;
        }
    }
    let set = direct::LightSet::new(&sc, vec![0]);
    let rec = Receiver::illuminance(DVec3::ZERO, DVec3::Z);
    let frame = Frame::from_normal(DVec3::Z);
    let stats = |strategy: Strategy| {
        let n = 400_000u64;
        let v: Vec<f64> = (0..n)
            .map(|s| {
                let mut rng = Philox4x32::new(11, s);
                direct::sample(&sc, &set, &rec, &frame, strategy, None, &mut rng)
            })
            .collect();
        let m = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / n as f64;
        let m4 = v.iter().map(|x| (x - m).powi(4)).sum::<f64>() / n as f64;
        (m, (var / n as f64).sqrt(), var.sqrt(), m4 / (var * var))
    };
    let (mean, se, sd, kurt) = stats(Strategy::Power);
    let z = (mean - exact) / se;
    assert!(z.abs() < sidak(1), "MIS {mean} +- {se} vs {exact} (z {z})");
    assert!(
        se / exact < 0.02 / sidak(1),
        "a 2 % error must fail: se {se}"
    );
    let (_, _, sd_light, _) = stats(Strategy::Light);
    assert!(
        sd < 1.2 * sd_light,
        "sd {sd} against light sampling's {sd_light}"
    );
    assert!(kurt < 20.0, "kurtosis {kurt}");
}

/// A point on a sphere light's surface is refused with a message that says
/// so and how to fix it (it read "its illuminance is not finite", which is
/// false there: the limit from outside is finite); 1e-9 m outside, the
/// exact direct term is that limit, `I / R^2` facing the sphere (`pi L`),
/// 0 facing away, `L (alpha - sin alpha cos alpha)` with `alpha = pi / 2`
/// sideways (half of `pi L`).
#[test]
fn a_point_on_a_sphere_light_is_refused_clearly_and_finite_just_outside() {
    let s = scene(
        r#"
[[light]]
type = "sphere"
name = "globe"
center = [5, 0, 2]
radius = 0.5
intensity = 100.0
"#,
    );
    let on = DVec3::new(5.0, 0.0, 1.5);
    let err = Receivers::new(&s, &[(on, DVec3::Z)])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("globe, a sphere light of radius 0.5 m centred at (5, 0, 2) m: place it outside the sphere"),
        "{err}"
    );
    let off = on - DVec3::Z * 1e-9;
    let rec = Receivers::new(&s, &[(off, DVec3::Z), (off, -DVec3::Z), (off, DVec3::X)]).unwrap();
    // At d = R + 1e-9 (sin alpha = R / d, L = I / (pi R^2)).
    let (d, l): (f64, f64) = (0.5 + 1e-9, 100.0 / (std::f64::consts::PI * 0.25));
    let a = (0.5 / d).asin();
    let want = [100.0 / (d * d), 0.0, l * (a - a.sin() * a.cos())];
    assert!((want[2] - 200.0).abs() < 0.02);
    for (j, w) in want.iter().enumerate() {
        let e = rec.direct()[j];
        assert!((e - w).abs() < 1e-6 * 400.0, "normal {j}: {e} vs {w}");
    }
}
