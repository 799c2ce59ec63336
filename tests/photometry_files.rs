//! The photometric test files of `data/photometry/` (written by
//! `generate.py` there from analytic distributions): every LM-63 version,
//! TILT=INCLUDE, types A, B and C, every horizontal symmetry, absolute
//! photometry, EULUMDAT Isym 0-4, several lamp sets, decimal commas, and an
//! IES/LDT pair of the same distribution that must give the same light.

use glam::DVec3;
use lumest::io::photometry::read;
use lumest::light::Goniometric;
use lumest::sampling::Philox4x32;
use std::f64::consts::PI;
use std::path::Path;

const I0: f64 = 1000.0;

fn dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data/photometry")
}

/// The analytic type C distribution of `generate.py` for a symmetry.
fn type_c(sym: &str, c: f64, g: f64) -> f64 {
    if g > PI / 2.0 {
        return 0.0;
    }
    let f = match sym {
        "rot" => 0.0,
        "quad" => 0.3 * (2.0 * c).cos(),
        "c0180" => 0.3 * c.cos(),
        "c90270" => 0.3 * c.sin(),
        "full" => 0.3 * c.cos() + 0.2 * (2.0 * c).sin(),
        _ => unreachable!(),
    };
    I0 * g.cos() * (1.0 + f)
}

/// The file's distribution in the luminaire's frame (nadir -z, C0 +x).
fn analytic(file: &str, d: DVec3) -> f64 {
    let g = (-d.z).clamp(-1.0, 1.0).acos();
    let c = d.y.atan2(d.x);
    let sym = match file {
        f if f.starts_with("lm63") || f.starts_with("tilt") || f == "isym1.ldt" => "rot",
        "lamp_sets.ldt" | "absolute_commas.ldt" => "rot",
        "sym_quadrant.ies" | "isym4.ldt" => "quad",
        "sym_c0_c180.ies" | "isym2.ldt" => "c0180",
        "sym_c90_c270.ies" | "isym3.ldt" => "c90270",
        "sym_full.ies" | "isym0.ldt" | "pair.ies" | "pair.ldt" => "full",
        "type_b.ies" | "type_a.ies" => {
            // Type B: V the plane's angle about the transverse axis y, H
            // the lateral angle out of it (LM-63, Radiance's ies2rad). Type
            // A: H the plane's angle about x, V the angle out of it.
            let (h, v) = if file == "type_b.ies" {
                (d.y.clamp(-1.0, 1.0).asin(), d.x.atan2(-d.z))
            } else {
                (d.y.atan2(-d.z), d.x.clamp(-1.0, 1.0).asin())
            };
            return if h.abs() <= PI / 2.0 && v.abs() <= PI / 2.0 {
                I0 * h.cos() * v.cos() * (1.0 + 0.4 * h.sin())
            } else {
                0.0
            };
        }
        other => panic!("no analytic distribution for {other}"),
    };
    type_c(sym, c, g)
}

const FILES: [&str; 21] = [
    "lm63_1986.ies",
    "lm63_1991.ies",
    "lm63_1995.ies",
    "lm63_2002.ies",
    "lm63_2019.ies",
    "tilt_include.ies",
    "sym_quadrant.ies",
    "sym_c0_c180.ies",
    "sym_c90_c270.ies",
    "sym_full.ies",
    "type_b.ies",
    "type_a.ies",
    "pair.ies",
    "isym0.ldt",
    "isym1.ldt",
    "isym2.ldt",
    "isym3.ldt",
    "isym4.ldt",
    "lamp_sets.ldt",
    "absolute_commas.ldt",
    "pair.ldt",
];

#[test]
fn every_file_holds_its_analytic_distribution_and_flux() {
    let mut rng = Philox4x32::new(5, 0);
    for f in FILES {
        let p = read(&dir().join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        let g = Goniometric::new(&p, 1.0);
        // Bilinear interpolation of cos over 5 degrees (10 for A and B) and
        // of the C dependence over 15 (0.3 cos 2C: (dC^2 / 8) 1.2 = 1.03e-2):
        // about 1e-2 of I0 at most; the grid nodes below are checked exactly.
        let ab = f.starts_with("type_");
        let tol = 1.2e-2 * I0;
        for _ in 0..4000 {
            let d = lumest::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
            let (got, want) = (g.intensity(d), analytic(f, d));
            assert!((got - want).abs() <= tol, "{f} at {d}: {got} vs {want}");
        }
        // On the grid nodes of the full circle the expansion by symmetry is exact.
        if !ab {
            for ci in 0..24 {
                for gi in 0..=18 {
                    let (c, gm) = (
                        (15.0 * ci as f64).to_radians(),
                        (5.0 * gi as f64).to_radians(),
                    );
                    let d = DVec3::new(gm.sin() * c.cos(), gm.sin() * c.sin(), -gm.cos());
                    // At the nadir, where every plane meets, the planes'
                    // mean: I0 (each file's C term, a sum of cos / sin of C
                    // and 2C, averages to 0 over a turn, and so does its
                    // trapezoidal mean over equally spaced planes).
                    let want = if gi == 0 { I0 } else { analytic(f, d) };
                    let got = g.intensity(d);
                    assert!(
                        (got - want).abs() <= 1e-5 * I0,
                        "{f} at C {ci} gamma {gi}: {got} vs {want}"
                    );
                }
            }
        }
        // Flux pi I0, to the interpolation's error.
        let rel = (g.power() / (PI * I0) - 1.0).abs();
        assert!(
            rel < if ab { 6e-3 } else { 1e-3 },
            "{f}: power {}",
            g.power()
        );
        // Nothing above the horizon for type C (measured 0-90 degrees only).
        if !ab {
            assert_eq!(
                g.intensity(DVec3::new(0.3, 0.1, 0.9).normalize()),
                0.0,
                "{f}"
            );
        }
    }
}

#[test]
fn versions_lamp_sets_and_absolute_photometry_read_as_documented() {
    let lumens = |f: &str| read(&dir().join(f)).unwrap().lamp_lumens;
    for f in [
        "lm63_1986.ies",
        "lm63_1991.ies",
        "lm63_1995.ies",
        "lm63_2002.ies",
        "lm63_2019.ies",
        "tilt_include.ies",
    ] {
        assert_eq!(lumens(f), Some(1000.0), "{f}");
    }
    assert_eq!(lumens("pair.ies"), None);
    assert_eq!(lumens("absolute_commas.ldt"), None);
    // The first of three lamp sets is the one the table refers to.
    assert_eq!(lumens("lamp_sets.ldt"), Some(1000.0));
    let format = |f: &str| read(&dir().join(f)).unwrap().format;
    assert_eq!(format("lm63_1986.ies"), "IES LM-63-1986");
    assert_eq!(format("lm63_2019.ies"), "IES LM-63-2019");
    // The 2019 file generation type (1.10001) never multiplies: same table as 2002.
    let a = read(&dir().join("lm63_2019.ies")).unwrap();
    let b = read(&dir().join("lm63_2002.ies")).unwrap();
    assert_eq!(a.candela, b.candela);
}

#[test]
fn the_ies_and_ldt_pair_give_the_same_illuminance() {
    let scene_with = |file: &str| {
        let kind = if file.ends_with(".ies") { "ies" } else { "ldt" };
        let src = format!(
            "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[surface]]\ntype = \"plane\"\npoint = [0, 0, 3]\nnormal = [0, 0, -1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[light]]\ntype = \"{kind}\"\nfile = \"{file}\"\nposition = [0.2, -0.1, 2.5]\nrotate = 30\n"
        );
        lumest::scene::parse(&src, &dir().join("pair.toml")).unwrap()
    };
    let (a, b) = (scene_with("pair.ies"), scene_with("pair.ldt"));
    assert!((a.total_power() / b.total_power() - 1.0).abs() < 1e-9);
    let pts: Vec<(DVec3, DVec3)> = (0..60)
        .map(|k| {
            let t = k as f64 * 0.37;
            (
                DVec3::new(
                    3.0 * t.cos() * (k as f64 / 60.0),
                    3.0 * t.sin() * (k as f64 / 60.0),
                    0.0,
                ),
                DVec3::Z,
            )
        })
        .collect();
    let (ra, rb) = (
        lumest::estimator::Receivers::new(&a, &pts).unwrap(),
        lumest::estimator::Receivers::new(&b, &pts).unwrap(),
    );
    for j in 0..pts.len() {
        let (x, y) = (ra.direct()[j], rb.direct()[j]);
        assert!(
            (x - y).abs() <= 1e-9 * x.max(1e-12),
            "point {j}: {x} vs {y}"
        );
        assert!(x > 0.0);
    }
    // The whole estimate too: the same tables give the same chains.
    let cfg = lumest::run::RunConfig {
        stop: lumest::run::Stop {
            chains: Some(20_000),
            ..Default::default()
        },
        threads: 1,
        ..Default::default()
    };
    let xa = lumest::estimator::local::run(&a, &ra, &cfg, &mut |_| true);
    let xb = lumest::estimator::local::run(&b, &rb, &cfg, &mut |_| true);
    for j in 0..pts.len() {
        let (x, y) = (
            xa.tallies.estimated[j].mean(),
            xb.tallies.estimated[j].mean(),
        );
        let se = xa.tallies.estimated[j].std_error();
        assert!(
            (x - y).abs() <= 1e-6 * x.max(1e-12) || ((x - y) / se).abs() < 4.0,
            "point {j}: {x} vs {y}"
        );
    }
}

/// The direct illuminance \[lx\] at `point` with normal `normal` from one
/// light of the IES file `text` written as `t.ies`, placed by `light` (the
/// TOML lines after `file`), with the scene's total flux \[lm\].
fn one_ies_light(text: &str, light: &str, point: DVec3, normal: DVec3) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("t.ies"), text).unwrap();
    let src = format!("[[light]]\ntype = \"ies\"\nfile = \"t.ies\"\n{light}\n");
    let scene = lumest::scene::parse(&src, &dir.path().join("s.toml")).unwrap();
    let r = lumest::estimator::Receivers::new(&scene, &[(point, normal)]).unwrap();
    (r.direct()[0], scene.total_power())
}

/// TILT=INCLUDE applies the factor at the installed tilt, by the file's
/// lamp-to-luminaire geometry (1 vertical: the aim's angle from straight
/// down; 2, 3 horizontal along C0 / C90: local x / y's inclination from the
/// horizontal), linear between the table's angles and clamped beyond. The
/// reviewer's tilt.ies (100 cd, factors 1, 0.8, 0.6 at 0, 45, 90 deg), aimed
/// 45 deg from down at a point 3 sqrt(2) m along the aim, facing it:
/// 100 x 0.8 / 18 = 4.4444 lx (5.5556 before: the factor at 0 deg). Then a
/// 100 cd table over the whole sphere (flux 400 pi lm) at tilts worked out
/// by hand: a point 3 m along the aim, facing the light, gets 100 f / 9 lx.
#[test]
fn tilt_factors_apply_at_the_installed_tilt() {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let reviewer = "IESNA:LM-63-2002\n[TEST] x\nTILT=INCLUDE\n1\n3\n0 45 90\n1.0 0.8 0.6\n\
                    1 -1 1 3 1 1 2 0 0 0\n1 1 50\n0 45 90\n0\n100 100 100\n";
    let (e, _) = one_ies_light(
        reviewer,
        "position = [0, 0, 3]\naim = [0.7071067811865476, 0, -0.7071067811865476]",
        DVec3::new(3.0, 0.0, 0.0),
        DVec3::new(-s, 0.0, s),
    );
    assert!((e - 80.0 / 18.0).abs() < 1e-9, "{e} lx, want 4.4444");
    let file = |geometry: u8| {
        format!(
            "IESNA:LM-63-2002\n[TEST] x\nTILT=INCLUDE\n{geometry}\n3\n0 45 90\n1.0 0.8 0.6\n\
             1 -1 1 3 1 1 2 0 0 0\n1 1 50\n0 90 180\n0\n100 100 100\n"
        )
    };
    let (s30, c30) = (0.5, 0.75f64.sqrt());
    // 30 deg: 1 + (0.8 - 1) 30 / 45.
    let f30 = 1.0 - 0.2 * 30.0 / 45.0;
    let cases: [(u8, [f64; 3], f64, f64); 12] = [
        (1, [0.0, 0.0, -1.0], 0.0, 1.0),
        (1, [s30, 0.0, -c30], 0.0, f30),
        // Turning about the aim changes nothing for a vertical lamp.
        (1, [0.0, s30, -c30], 77.0, f30),
        (1, [1.0, 0.0, 0.0], 0.0, 0.6),
        // Straight up: tilt 180, past the table's 90: its last factor.
        (1, [0.0, 0.0, 1.0], 0.0, 0.6),
        // Aimed 30 deg towards +x: C0 (local x) rises 30 deg, C90 stays level.
        (2, [s30, 0.0, -c30], 0.0, f30),
        (3, [s30, 0.0, -c30], 0.0, 1.0),
        // Turned 90 deg about the aim: C0 level, C90 rises 30 deg.
        (2, [s30, 0.0, -c30], 90.0, 1.0),
        (3, [s30, 0.0, -c30], 90.0, f30),
        // Aimed along +y: C0 stays +x (level); turned 90, C0 points up.
        (2, [0.0, 1.0, 0.0], 0.0, 1.0),
        (2, [0.0, 1.0, 0.0], 90.0, 0.6),
        // Upright (down, C0 along +x): tilt 0 for every geometry.
        (3, [0.0, 0.0, -1.0], 0.0, 1.0),
    ];
    for (geometry, aim, rotate, f) in cases {
        let a = DVec3::from(aim);
        let (e, power) = one_ies_light(
            &file(geometry),
            &format!(
                "position = [0, 0, 5]\naim = [{}, {}, {}]\nrotate = {rotate}",
                aim[0], aim[1], aim[2]
            ),
            DVec3::new(0.0, 0.0, 5.0) + 3.0 * a,
            -a,
        );
        let want = 100.0 * f / 9.0;
        assert!(
            (e - want).abs() < 1e-9 * want,
            "geometry {geometry}, aim {aim:?}, rotate {rotate}: {e} lx, want {want}"
        );
        assert!(
            (power - 400.0 * PI * f).abs() < 1e-9 * power,
            "geometry {geometry}: {power} lm"
        );
    }
    // `flux` rescales the file's table; the tilt factor multiplies on top:
    // 1000 lm at 45 deg emits 800 lm.
    let (_, power) = one_ies_light(
        &file(1),
        "position = [0, 0, 5]\naim = [0.7071067811865476, 0, -0.7071067811865476]\nflux = 1000",
        DVec3::ZERO,
        DVec3::Z,
    );
    assert!((power - 800.0).abs() < 1e-9, "{power} lm");
}
