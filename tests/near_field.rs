//! The singular kernel and its remedy: a point 1 mm above a lit floor,
//! facing it. The plain local estimate's kernel `cos cos / d^2` is
//! unbounded there (collisions a fraction of a millimetre away score ~1e6
//! times the typical value): its tally is flagged. The near/far split
//! (`--near-radius`) bounds the kernel and estimates the near part by
//! backward paths; it agrees with the exact value and passes the checks.

mod common;
use common::{chains_cfg, from_floor};
use glam::DVec3;
use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::reference::Sobolev;
use lumest::run::RunConfig;
use lumest::tally::sidak_bound;

#[test]
fn near_field_split_tames_the_singular_kernel_next_to_a_lit_floor() {
    let (rho, dz) = (0.5, 1e-3);
    let s = Sobolev::new(0.5, 0.5, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    // Facing the floor from 1 mm, and an ordinary point for comparison.
    let pts = [
        (DVec3::new(0.0, 0.0, dz), -DVec3::Z),
        (DVec3::new(0.0, 0.0, 0.5 - 0.25), -DVec3::Z),
    ];
    let exact = [
        from_floor(rho, dz, |x| s.illuminance(1, x).e),
        from_floor(rho, 0.25, |x| s.illuminance(1, x).e),
    ];
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let plain_cfg = RunConfig {
        near_auto: false,
        ..chains_cfg(200_000, 5, 0)
    };
    let plain = run(&case.scene, &rec, &plain_cfg, &mut |_| true);
    let near_cfg = RunConfig {
        near: (0.05, 16),
        ..chains_cfg(200_000, 5, 0)
    };
    let split = run(&case.scene, &rec, &near_cfg, &mut |_| true);
    let bound = sidak_bound(1e-3, 2, None);
    for (name, r) in [("plain", &plain), ("split", &split)] {
        let w = &r.tallies.estimated[0];
        eprintln!(
            "{name}: E = {} +- {} (exact {}), R {:.2e}, VOV {:.3}, flag {}, {:.2} s, FOM {:.3e}",
            w.mean(),
            w.std_error(),
            exact[0],
            w.std_error() / w.mean(),
            w.vov(),
            r.tallies.diagnostics(0, 0.0).flag(),
            r.wall,
            lumest::tally::figure_of_merit(w.std_error() / w.mean(), r.wall)
        );
    }
    // The plain estimate's tally is not trustworthy, and says so: the
    // `near` check flags the point 1 mm from the floor, not the ordinary one.
    assert!(plain.tallies.diagnostics(0, 0.0).flag().contains("near"));
    assert!(!plain.tallies.diagnostics(1, 0.0).flag().contains("near"));
    // The split is right, within its honest error bar, and passes every check.
    for (j, &ex) in exact.iter().enumerate() {
        let w = &split.tallies.estimated[j];
        let z = (w.mean() - ex) / w.std_error();
        assert!(
            z.abs() < bound,
            "point {j}: {} +- {} vs {} (z {z})",
            w.mean(),
            w.std_error(),
            ex
        );
        assert_eq!(split.tallies.diagnostics(j, 0.0).flag(), "ok", "point {j}");
    }
    // The ordinary point is unaffected by the split beyond noise.
    let (a, b) = (&plain.tallies.estimated[1], &split.tallies.estimated[1]);
    assert!(((a.mean() - b.mean()) / a.std_error().hypot(b.std_error())).abs() < bound);
}

#[test]
fn near_field_split_is_reproducible_for_any_thread_count() {
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let pts = [(DVec3::new(0.3, 0.0, 1e-3), -DVec3::Z)];
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let go = |t| {
        let cfg = RunConfig {
            near: (0.02, 8),
            ..chains_cfg(20_000, 9, t)
        };
        run(&case.scene, &rec, &cfg, &mut |_| true)
            .tallies
            .estimated[0]
            .mean()
    };
    assert_eq!(go(1).to_bits(), go(2).to_bits());
}

#[test]
fn automatic_near_field_splits_only_where_a_surface_is_close() {
    // Auto radius: a quarter of the distance to the light, where a surface
    // lies within a tenth of it. The point 1 mm above the floor gets the
    // split (and the exact answer); the point in the middle of the room
    // gets exactly the plain estimate.
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let pts = [
        (DVec3::new(0.0, 0.0, 1e-3), -DVec3::Z),
        (DVec3::new(0.3, 0.0, 0.5), DVec3::Z),
    ];
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let auto = rec.clone().with_auto_near_field(&case.scene, 16);
    let (paths, radii) = auto.near_field();
    assert_eq!(paths, 16);
    assert!(
        (radii[0] - 0.25 * 0.499).abs() < 1e-12 && radii[1] == 0.0,
        "{radii:?}"
    );
    let cfg = chains_cfg(100_000, 8, 0);
    let plain = run(&case.scene, &rec, &cfg, &mut |_| true);
    let split = run(&case.scene, &auto, &cfg, &mut |_| true);
    let exact = from_floor(0.5, 1e-3, |x| s.illuminance(1, x).e);
    let w = &split.tallies.estimated[0];
    assert!(((w.mean() - exact) / w.std_error()).abs() < sidak_bound(1e-3, 1, None));
    assert_eq!(
        plain.tallies.estimated[1].mean().to_bits(),
        split.tallies.estimated[1].mean().to_bits()
    );
}

/// The error bars of far points between the Sobolev planes (h = 0.5, rho
/// = 0.5, points on the floor at r = 20 and 30) at the default settings
/// users run (`--near-radius auto`, 20,000 chains), over 60 seeds: the
/// mean z^2 against the exact solution (independent runs, so about 1.07 for
/// 32 batches) stays below 1.6, and fewer than 8 % of the z fall below
/// -1.96. With the auto radius at a tenth of the distance to the light the
/// points' light from 3-10 m around them came from rare light-tracing
/// collisions: mean z^2 1.73 and 11.7 % below -1.96 on these runs (the
/// misses all low, to z = -7 on other seeds), which fails both bounds; at
/// a quarter, 1.09 and 1.7 %.
#[test]
fn far_points_between_planes_have_calibrated_error_bars() {
    use std::process::Command;
    let dir = std::env::temp_dir().join(format!("lumest-far-cal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let points = dir.join("p.csv");
    std::fs::write(&points, "x,y,z,nx,ny,nz\n20,0,0,0,0,1\n30,0,0,0,0,1\n").unwrap();
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let exact = [s.illuminance(1, 20.0).e, s.illuminance(1, 30.0).e];
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sobolev.toml");
    let out = dir.join("e.csv");
    let mut zs = Vec::new();
    for seed in 1..=60 {
        let st = Command::new(env!("CARGO_BIN_EXE_lumest"))
            .args([
                "illuminance",
                "--scene",
                scene,
                "--chains",
                "20000",
                "--threads",
                "1",
            ])
            .args(["--seed", &seed.to_string()])
            .arg("--points")
            .arg(&points)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            st.status.success(),
            "{}",
            String::from_utf8_lossy(&st.stderr)
        );
        let text = std::fs::read_to_string(&out).unwrap();
        for (line, e) in text.lines().skip(1).zip(exact) {
            let f: Vec<f64> = line
                .split(',')
                .map(|v| v.parse().unwrap_or(f64::NAN))
                .collect();
            zs.push((f[6] - e) / f[7]);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    let n = zs.len() as f64;
    let z2 = zs.iter().map(|z| z * z).sum::<f64>() / n;
    let low = zs.iter().filter(|z| **z < -1.96).count() as f64 / n;
    assert!(z2.is_finite() && z2 < 1.6, "mean z^2 {z2}: {zs:?}");
    assert!(low < 0.08, "{low} of the z below -1.96: {zs:?}");
}

/// In a scene lit from infinity alone (here the sun through a skylight)
/// the `near` check still flags a point in a room's corner, 1 mm from two
/// walls and the floor, where the plain local estimate misses much of the
/// light reflected right around it (the near/far split is off in such
/// scenes; a reviewer measured 658 for 929 lx): the scale is the median
/// distance of the surfaces around the point. Not flagged: the middle of
/// the room, and a point on an open floor under the sky. The old build
/// measured the scale from finite lights alone, of which there are none.
#[test]
fn daylit_corner_points_are_flagged_near() {
    use lumest::estimator::near_need;
    use lumest::sampling::warp::Frame;
    let lambert = "material = { type = \"lambertian\", reflectance = 0.6 }";
    let rect = |name: &str, c: [f64; 3], e1: [f64; 3], e2: [f64; 3]| {
        format!(
            "[[surface]]\ntype = \"rectangle\"\nname = \"{name}\"\ncorner = {c:?}\nedge1 = {e1:?}\n\
             edge2 = {e2:?}\nsides = \"both\"\n{lambert}\n"
        )
    };
    // A 6 x 4 x 3 m room on an infinite floor, its ceiling open in a 1 x 1
    // m skylight over the middle, the sun high above.
    let mut src = format!(
        "[[surface]]\ntype = \"plane\"\nname = \"floor\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n{lambert}\n"
    );
    for (name, c, e1, e2) in [
        ("wall x0", [0.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 3.0]),
        ("wall x6", [6.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 3.0]),
        ("wall y0", [0.0, 0.0, 0.0], [6.0, 0.0, 0.0], [0.0, 0.0, 3.0]),
        ("wall y4", [0.0, 4.0, 0.0], [6.0, 0.0, 0.0], [0.0, 0.0, 3.0]),
        (
            "ceiling a",
            [0.0, 0.0, 3.0],
            [2.5, 0.0, 0.0],
            [0.0, 4.0, 0.0],
        ),
        (
            "ceiling b",
            [3.5, 0.0, 3.0],
            [2.5, 0.0, 0.0],
            [0.0, 4.0, 0.0],
        ),
        (
            "ceiling c",
            [2.5, 0.0, 3.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.5, 0.0],
        ),
        (
            "ceiling d",
            [2.5, 2.5, 3.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.5, 0.0],
        ),
    ] {
        src += &rect(name, c, e1, e2);
    }
    src += "[[light]]\ntype = \"sun\"\nsun_altitude = 80\nsun_azimuth = 30\nilluminance = 80000\n";
    let scene = lumest::scene::parse(&src, std::path::Path::new("skylight.toml")).unwrap();
    let need = |p: DVec3, n: DVec3| near_need(&scene, p, &Frame::from_normal(n.normalize()), false);
    let corner = need(DVec3::new(5.999, 3.999, 0.001), DVec3::new(-1.0, -1.0, 1.0));
    assert!(corner > 0.0, "the corner point needs the split: {corner}");
    assert_eq!(
        need(DVec3::new(3.0, 2.0, 0.75), DVec3::Z),
        0.0,
        "the middle"
    );
    assert_eq!(
        need(DVec3::new(20.0, 20.0, 0.001), DVec3::Z),
        0.0,
        "the open floor"
    );
    let rec = Receivers::new(
        &scene,
        &[(
            DVec3::new(5.999, 3.999, 0.001),
            DVec3::new(-1.0, -1.0, 1.0).normalize(),
        )],
    )
    .unwrap();
    assert!(
        rec.near_plain(0),
        "flagged near: the split is off in a scene lit from infinity"
    );
}

/// A near part whose radius reaches the source (a point 0.2 m above the
/// floor facing it, over a source 1 cm above the floor; radius 0.3 m): its
/// paths' vertices come next to the source, where next-event estimation
/// spikes, and there (only) the paths make light-guided connections
/// (`backward::guides`). Both ways agree with the exact reflected light;
/// with the connections the error bar is much smaller (without them the
/// near part is right but heavy-tailed).
#[test]
fn a_near_part_reaching_the_source_is_guided() {
    let (h1, rho, dz) = (0.01, 0.9, 0.2);
    let s = Sobolev::new(h1, 1.0 - h1, rho, rho, 1.0).unwrap();
    let case = sobolev_case(&s, 2, 1.0);
    let pts = [(DVec3::new(0.0, 0.0, dz), -DVec3::Z)];
    let exact = from_floor(rho, dz, |x| s.illuminance(1, x).e);
    let rec = Receivers::new(&case.scene, &pts).unwrap();
    let cfg = |guide| RunConfig {
        near: (0.3, 64),
        ..guided_cfg(guide, 7)
    };
    let on = run(&case.scene, &rec, &cfg(true), &mut |_| true);
    let off = run(&case.scene, &rec, &cfg(false), &mut |_| true);
    let bound = sidak_bound(1e-3, 2, None);
    let mut se = [0.0; 2];
    for (k, (name, r)) in [("guided", &on), ("plain", &off)].into_iter().enumerate() {
        let w = &r.tallies.estimated[0];
        se[k] = w.std_error();
        eprintln!(
            "{name}: E = {} +- {} (exact {exact}), VOV {:.3}",
            w.mean(),
            se[k],
            w.vov()
        );
        let z = (w.mean() - exact) / se[k];
        assert!(
            z.abs() < bound,
            "{name}: {} +- {} vs {exact} (z {z})",
            w.mean(),
            se[k]
        );
    }
    assert!(se[0] < 0.5 * se[1], "guided {} vs plain {}", se[0], se[1]);
}

/// Under a narrow spot (outer half-angle 2 degrees, 0.3 m from a wall) the
/// next-event estimate over a near part's region jumps from 0 to
/// `I / h^2` across the beam's footprint whatever the distance to the
/// light, so every vertex keeps its light-guided connections
/// (`backward::peaked_lights`; with them only where the region reaches
/// the light, a reviewer measured error bars 9-41 times wider, and `R`
/// flags). Points by the wall's foot and on the floor beside it: the
/// default agrees with the unguided near part, and its error bars are a
/// fraction of the unguided ones.
#[test]
fn near_parts_under_a_narrow_spot_stay_guided() {
    let scene = lumest::scene::parse(
        r#"
[[surface]]
type = "box"
min = [0, 0, 0]
max = [4, 4, 3]
normals = "inward"
material = { type = "lambertian", reflectance = 0.7 }

[[light]]
type = "spot"
position = [0.3, 2.0, 2.9]
direction = [0, 0, -1]
inner = 1.0
outer = 2.0
intensity = 10000.0
"#,
        std::path::Path::new("spot.toml"),
    )
    .unwrap();
    let pts = [
        (DVec3::new(0.01, 2.0, 0.05), DVec3::X),
        (DVec3::new(0.01, 2.3, 0.1), DVec3::X),
        (DVec3::new(0.1, 2.0, 0.001), DVec3::Z),
        (DVec3::new(0.05, 2.3, 0.001), DVec3::Z),
    ];
    let rec = Receivers::new(&scene, &pts).unwrap();
    let cfg = |guide| guided_cfg(guide, 2);
    let on = run(&scene, &rec, &cfg(true), &mut |_| true);
    let off = run(&scene, &rec, &cfg(false), &mut |_| true);
    let bound = sidak_bound(1e-3, pts.len(), None);
    for j in 0..pts.len() {
        let (a, b) = (&on.tallies.estimated[j], &off.tallies.estimated[j]);
        let z = (a.mean() - b.mean()) / a.std_error().hypot(b.std_error());
        eprintln!(
            "point {j}: guided {} +- {}, plain {} +- {}",
            a.mean(),
            a.std_error(),
            b.mean(),
            b.std_error()
        );
        assert!(z.abs() < bound, "point {j}: z = {z}");
        assert!(
            a.std_error() < 0.3 * b.std_error(),
            "point {j}: guided {} vs plain {}",
            a.std_error(),
            b.std_error()
        );
        assert_eq!(
            on.tallies.diagnostics(j, on.direct[j]).flag(),
            "ok",
            "point {j}"
        );
    }
}

/// 100,000 chains of seed `seed`, the backward paths with light-guided
/// connections (`guide`) or without.
fn guided_cfg(guide: bool, seed: u64) -> RunConfig {
    RunConfig {
        chain: lumest::chain::ChainParams {
            guide,
            ..lumest::chain::ChainParams::default()
        },
        ..chains_cfg(100_000, seed, 0)
    }
}

/// A plane of reflectance 0.5 through the origin facing up, and `light`.
fn plane_under(light: &str) -> lumest::scene::Scene {
    let src = format!(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\n[[light]]\n{light}"
    );
    lumest::scene::parse(&src, std::path::Path::new("plane.toml")).unwrap()
}

/// Points `pts` of `scene` against `exact` over `seeds` runs of `chains`
/// chains (seeds from `seed0`): every |z| within the Sidak bound over all
/// of them, and the mean of z^2 (about 1.07 for 32 batches) below 2.5.
fn calibrated(
    scene: &lumest::scene::Scene,
    pts: &[(DVec3, DVec3)],
    exact: &[f64],
    (seeds, seed0, chains): (u64, u64, u64),
) {
    let rec = Receivers::new(scene, pts).unwrap();
    let bound = sidak_bound(1e-3, seeds as usize * pts.len(), Some(32));
    let mut z2 = 0.0;
    for seed in seed0..seed0 + seeds {
        let r = run(scene, &rec, &chains_cfg(chains, seed, 2), &mut |_| true);
        for (j, &e) in exact.iter().enumerate() {
            let z = common::z(&r, j, e);
            assert!(
                z.abs() < bound,
                "point {:?}, seed {seed}: z = {z}",
                pts[j].0
            );
            z2 += z * z;
        }
    }
    let mean = z2 / (seeds as usize * pts.len()) as f64;
    assert!(mean < 2.5, "mean z^2 {mean}");
}

/// Points a fraction of a millimetre to a few millimetres above an evenly
/// lit ground (the sun over an infinite plane), facing it, read `rho E_h`
/// exactly; their near paths leave the split radius only in grazing
/// directions, one in 10^5-10^7 (`(h / R)^2`). Drawn from the plain cosine
/// no run saw one: the near part read `1 / (1 - p)` high with an error bar
/// of nearly nothing (z 30-300 over seeds, flagged `ok`; the mean of z^2
/// in the thousands). With the first direction stratified
/// (`lumest::estimator::first_band`) the grazing strata see them in every
/// run: calibrated over seeds. Under a lamp (1000 cd, 1 m up) the ground's
/// illuminance falls off across the distances the paths reach, `h tan
/// theta`, a heavy tail in every decade of `cos^2 theta`: 0.1 mm up the
/// plain cosine read 1e-7 high on most runs (mean z^2 about 9, coverage
/// 27 of 40).
#[test]
fn points_just_above_a_sunlit_ground_have_calibrated_error_bars() {
    lit_floor_calibrated(
        [2e-4, 2e-3],
        (12, 100, 16_384),
        [1e-4, 1e-3],
        (16, 200, 20_000),
    );
}

/// Points facing a floor of reflectance 0.5 at heights `sun_h` \[m\] under
/// the sun (50,000 lx, read `rho E_h`) and at `lamp_h` under a 1000 cd lamp
/// 1 m up (the floor's light by quadrature, [`from_floor`]), each
/// [`calibrated`] over its `(seeds, first seed, chains)`.
fn lit_floor_calibrated(
    sun_h: [f64; 2],
    sun_runs: (u64, u64, u64),
    lamp_h: [f64; 2],
    lamp_runs: (u64, u64, u64),
) {
    let rho = 0.5;
    let mut sun =
        plane_under("type = \"distant\"\ndirection = [-0.5, -0.4, -0.6]\nilluminance = 50000\n");
    let e_h = 50000.0 * 0.6 / (0.25f64 + 0.16 + 0.36).sqrt();
    let pts: Vec<_> = sun_h
        .iter()
        .map(|&h| (DVec3::new(0.3, 0.2, h), -DVec3::Z))
        .collect();
    sun.fit_directional(&pts.iter().map(|p| p.0).collect::<Vec<_>>());
    calibrated(&sun, &pts, &[rho * e_h; 2], sun_runs);

    let lamp = plane_under("type = \"point\"\nposition = [0, 0, 1]\nintensity = 1000\n");
    let pts: Vec<_> = lamp_h
        .iter()
        .map(|&h| (DVec3::new(0.0, 0.0, h), -DVec3::Z))
        .collect();
    let exact: Vec<f64> = lamp_h
        .iter()
        .map(|&h| from_floor(rho, h, |s| 1000.0 / (1.0 + s * s).powf(1.5)))
        .collect();
    calibrated(&lamp, &pts, &exact, lamp_runs);
}

/// Short runs (2000 chains, 32 batches of about 62: one or two grazing
/// paths per batch) stay calibrated next to a lit floor: the grazing
/// stratum, twice the escape share wide (`first_band::GRAZE`), sees an
/// escape in about every second path. When it was eight times as wide,
/// one run in about seventy saw none among its 32 grazing paths and read
/// the far part's share twice with an error bar that missed it: z 11-22,
/// flagged `ok` (mean z^2 5-13 over 40-80 seeds).
#[test]
fn short_runs_next_to_a_lit_floor_have_calibrated_error_bars() {
    lit_floor_calibrated([1e-5, 1e-4], (60, 300, 2000), [1e-4, 1e-3], (60, 400, 2000));
}

/// The strata go where the near paths' values are steady (the pilot's
/// relative variance per path at most `first_band::STEADY`): a point 1 mm
/// above a floor under a lamp, facing it, takes them; a point 1 mm off the
/// office cabinet's back in the dark 5 cm gap behind it, facing it, where
/// multi-bounce light makes every path's value noisy, keeps the plain
/// cosine (there the strata cost 4-7 times the variance; a reviewer's
/// find: one run 6 standard errors low, flagged `ok`).
#[test]
fn near_strata_only_where_the_near_paths_are_steady() {
    let bands = |scene: &lumest::scene::Scene, p: DVec3, n: DVec3| {
        let mut rec = Receivers::new(scene, &[(p, n)]).unwrap();
        lumest::estimator::local::prepare(scene, &mut rec, &RunConfig::default());
        assert!(rec.near_field().1[0] > 0.0, "no near part at {p}");
        rec.near_bands(scene)[0]
    };
    let lamp = plane_under("type = \"point\"\nposition = [0, 0, 1]\nintensity = 1000\n");
    let b = bands(&lamp, DVec3::new(0.3, 0.0, 1e-3), -DVec3::Z);
    assert!(b > 0.0, "the floor point under the lamp takes no strata");
    let office = lumest::scene::load(std::path::Path::new("data/office.toml")).unwrap();
    let b = bands(&office, DVec3::new(0.9, 3.951, 0.6), -DVec3::Y);
    assert_eq!(b, 0.0, "the point in the cabinet's gap takes strata");
}
