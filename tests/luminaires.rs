//! Goniometric luminaires from photometric files, end to end: scene keys,
//! emission, the exact direct term and both estimators, against closed
//! forms and the exact Sobolev solution.

mod common;
use common::{chains_cfg, z};
use glam::DVec3;
use lumest::cases::sobolev::sobolev_case;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::light::Light;
use lumest::reference::Sobolev;
use lumest::scene::Scene;
use lumest::tally::sidak_bound;

/// An IES (LM-63-2002, type C, one C-plane) with `intensity(gamma)` \[cd\] at
/// the given vertical angles \[deg\].
fn ies(v: &[f64], intensity: impl Fn(f64) -> f64) -> String {
    let vals: Vec<String> = v
        .iter()
        .map(|&g| format!("{:.17e}", intensity(g)))
        .collect();
    let angles: Vec<String> = v.iter().map(|g| g.to_string()).collect();
    format!(
        "IESNA:LM-63-2002\n[TEST] lumest\nTILT=NONE\n1 -1 1 {} 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
        v.len(),
        angles.join(" "),
        vals.join(" ")
    )
}

/// The Sobolev planes (floor z = 0, ceiling z = 1) with the luminaire file
/// `name` at the source position instead of the point light.
fn sobolev_scene_with(
    dir: &std::path::Path,
    name: &str,
    text: &str,
    rho: f64,
    h1: f64,
    extra: &str,
) -> Scene {
    std::fs::write(dir.join(name), text).unwrap();
    let ext = name.rsplit('.').next().unwrap();
    let scene = format!(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = {{ type = \"lambertian\", reflectance = {rho} }}\n\
         [[surface]]\ntype = \"plane\"\npoint = [0, 0, 1]\nnormal = [0, 0, -1]\n\
         material = {{ type = \"lambertian\", reflectance = {rho} }}\n\
         [[light]]\ntype = \"{ext}\"\nname = \"lum\"\nfile = \"{name}\"\nposition = [0, 0, {h1}]\n{extra}"
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    lumest::scene::load(&path).unwrap()
}

#[test]
fn an_isotropic_table_reproduces_the_exact_sobolev_solution() {
    // 1 cd everywhere (gamma 0-180): the Sobolev problem exactly, through
    // the file parser, the table's emission sampler and both estimators.
    let dir = tempfile::tempdir().unwrap();
    let text = ies(&[0.0, 60.0, 120.0, 180.0], |_| 1.0);
    let scene = sobolev_scene_with(dir.path(), "iso.ies", &text, 0.5, 0.5, "");
    assert!(matches!(scene.lights[0], Light::Gonio { .. }));
    assert!((scene.total_power() / (4.0 * std::f64::consts::PI) - 1.0).abs() < 1e-12);
    let s = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0).unwrap();
    let case = sobolev_case(&s, 12, 3.0);
    let rec = Receivers::new(&scene, &case.points).unwrap();
    let fwd = run(&scene, &rec, &chains_cfg(100_000, 5, 0), &mut |_| true);
    let bwd = lumest::backward::run(&scene, &rec, &chains_cfg(2_000, 6, 0), &mut |_| true);
    let bound = sidak_bound(1e-3, 2 * case.points.len(), Some(32));
    for (j, ex) in case.exact.iter().enumerate() {
        assert!(
            (fwd.direct[j] / ex.e_direct - 1.0).abs() < 1e-12,
            "point {j}: direct"
        );
        for (name, r) in [("local", &fwd), ("backward", &bwd)] {
            let zj = z(r, j, ex.e);
            assert!(zj.abs() < bound, "{name} point {j}: z = {zj}");
            assert_eq!(
                r.tallies.diagnostics(j, r.direct[j]).flag(),
                "ok",
                "{name} point {j}"
            );
        }
    }
}

#[test]
fn a_cosine_downlight_gives_i0_h2_over_d4_and_nothing_upward() {
    // I = I0 cos(gamma) over 0-90 degrees in 1 degree steps: on the floor
    // E = I0 h^2 / d^4 (the bilinear table is within 4e-5 of cos), and the
    // ceiling gets no direct light at all (zero above the measured range).
    let dir = tempfile::tempdir().unwrap();
    let v: Vec<f64> = (0..=90).map(f64::from).collect();
    let i0 = 800.0;
    let text = ies(&v, |g| i0 * g.to_radians().cos());
    let h = 0.75;
    let scene = sobolev_scene_with(dir.path(), "cos.ies", &text, 0.0, h, "");
    // Flux pi I0 (a cosine emitter), exact for the interpolant up to 1e-4.
    let phi = scene.total_power();
    assert!(
        (phi / (std::f64::consts::PI * i0) - 1.0).abs() < 1e-4,
        "{phi}"
    );
    for r in [0.0, 0.3, 1.0, 2.5, 10.0] {
        let floor = Receivers::new(&scene, &[(DVec3::new(r, 0.2 * r, 0.0), DVec3::Z)]).unwrap();
        let d2 = r * r * 1.04 + h * h;
        let exact = i0 * h * h / (d2 * d2);
        let e = floor.direct()[0];
        assert!((e / exact - 1.0).abs() < 1e-4, "r = {r}: {e} vs {exact}");
        let ceiling = Receivers::new(&scene, &[(DVec3::new(r, 0.0, 1.0), -DVec3::Z)]).unwrap();
        assert_eq!(ceiling.direct()[0], 0.0, "r = {r}");
    }
    // Aimed up instead (`aim = [0, 0, 1]`): the roles swap.
    let up = sobolev_scene_with(dir.path(), "cos.ies", &text, 0.0, h, "aim = [0, 0, 1]\n");
    let rec = Receivers::new(
        &up,
        &[
            (DVec3::new(0.5, 0.0, 1.0), -DVec3::Z),
            (DVec3::new(0.5, 0.0, 0.0), DVec3::Z),
        ],
    )
    .unwrap();
    let up_h = 1.0 - h;
    let d2 = 0.25 + up_h * up_h;
    assert!((rec.direct()[0] / (i0 * up_h * up_h / (d2 * d2)) - 1.0).abs() < 1e-4);
    assert_eq!(rec.direct()[1], 0.0);
}

#[test]
fn an_asymmetric_luminaire_agrees_between_the_estimators() {
    // The seed's pendant (LM-63-1995, 73 vertical angles), tilted and turned
    // between reflecting planes: the local estimate's chains sample its
    // table, the backward estimator evaluates it at every vertex and draws
    // its guided photons from it; totals agree by z. `flux` rescales it.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("data/pendant.ies").unwrap();
    let scene = sobolev_scene_with(
        dir.path(),
        "pendant.ies",
        &text,
        0.6,
        0.4,
        "aim = [0.3, 0.1, -1]\nrotate = 30\nflux = 1000\n",
    );
    assert!((scene.total_power() / 1000.0 - 1.0).abs() < 1e-12);
    let s = Sobolev::new(0.4, 0.6, 0.6, 0.6, 1.0).unwrap();
    let case = sobolev_case(&s, 8, 2.0);
    let rec = Receivers::new(&scene, &case.points).unwrap();
    let fwd = run(&scene, &rec, &chains_cfg(100_000, 7, 0), &mut |_| true);
    let bwd = lumest::backward::run(&scene, &rec, &chains_cfg(2_000, 8, 0), &mut |_| true);
    let bound = sidak_bound(1e-3, case.points.len(), None);
    for j in 0..case.points.len() {
        let (a, b) = (&fwd.tallies.estimated[j], &bwd.tallies.estimated[j]);
        assert_eq!(fwd.direct[j], bwd.direct[j]);
        let zz = (a.mean() - b.mean()) / a.std_error().hypot(b.std_error());
        assert!(
            zz.abs() < bound,
            "point {j}: {} vs {} (z {zz})",
            a.mean(),
            b.mean()
        );
        assert!(a.std_error() < 0.02 * a.mean(), "point {j}: R too large");
    }
}

#[test]
fn bad_luminaire_keys_name_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.ies"), ies(&[0.0, 90.0], |_| 1.0)).unwrap();
    for (light, field) in [
        ("type = \"ies\"\nposition = [0, 0, 0.5]\n", "file"),
        (
            "type = \"ies\"\nfile = \"missing.ies\"\nposition = [0, 0, 0.5]\n",
            "file",
        ),
        (
            "type = \"ldt\"\nfile = \"a.ies\"\nposition = [0, 0, 0.5]\n",
            "file",
        ),
        (
            "type = \"ies\"\nfile = \"a.ies\"\nposition = [0, 0, 0.5]\nintensity = 3\n",
            "intensity",
        ),
        (
            "type = \"ies\"\nfile = \"a.ies\"\nposition = [0, 0, 0.5]\nflux = 1\nmultiplier = 2\n",
            "multiplier",
        ),
        (
            "type = \"ies\"\nfile = \"a.ies\"\nposition = [0, 0, 0.5]\naim = [0, 0, 0]\n",
            "aim",
        ),
        (
            "type = \"point\"\nposition = [0, 0, 0.5]\nintensity = 1\nfile = \"a.ies\"\n",
            "file",
        ),
    ] {
        let text = format!(
            "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n[[light]]\n{light}"
        );
        let path = dir.path().join("s.toml");
        std::fs::write(&path, text).unwrap();
        let e = lumest::scene::load(&path).unwrap_err().to_string();
        assert!(
            e.contains(&format!("field `{field}`")) && e.contains("s.toml:"),
            "{light}: {e}"
        );
    }
}

/// The office example with its photometric luminaires (five recessed
/// downlights from an LDT file on the ceiling plane, the seed-001 pendant
/// from its IES file): the two estimators, which share no estimator code,
/// agree on a sample of its work-plane grid.
#[test]
fn the_office_with_photometric_luminaires_agrees_between_the_estimators() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let scene = lumest::scene::load(&dir.join("office.toml")).unwrap();
    assert_eq!(scene.summary().goniometric_lights, 6);
    let grid = lumest::io::read_points(dir.join("office_grid.csv").to_str().unwrap()).unwrap();
    let points: Vec<_> = grid.points.iter().copied().step_by(11).collect();
    let rec = lumest::estimator::Receivers::new(&scene, &points).unwrap();
    let a = lumest::estimator::local::run(
        &scene,
        &rec,
        &common::chains_cfg(100_000, 1, 2),
        &mut |_| true,
    );
    let b = lumest::backward::run(&scene, &rec, &common::chains_cfg(3_000, 2, 2), &mut |_| {
        true
    });
    for j in 0..points.len() {
        let ea = a.direct[j] + a.tallies.estimated[j].mean();
        let eb = b.direct[j] + b.tallies.estimated[j].mean();
        let se = (a.tallies.estimated[j].std_error().powi(2)
            + b.tallies.estimated[j].std_error().powi(2))
        .sqrt();
        assert!(
            ea > 100.0 && ((ea - eb) / se).abs() < 4.0,
            "point {j}: local {ea} vs backward {eb} +- {se}"
        );
    }
}
