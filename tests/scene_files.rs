//! Scene files with every shape: what the compiled scene holds (and leaves
//! out), clear errors naming the line and field, the office example against
//! a pinned independent reference, the SH sphere written inline against the
//! integrating sphere's exact answer, and `lumest sh-fit`.

mod common;

use assert_cmd::Command;
use glam::DVec3;
use lumest::estimator::local::run;
use lumest::estimator::{Receiver, Receivers};
use lumest::geometry::mesh::star_blob;
use lumest::run::{RunConfig, Stop};
use lumest::scene;
use std::path::Path;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

fn parse(text: &str) -> Result<lumest::scene::Scene, String> {
    scene::parse(text, Path::new("test.toml")).map_err(|e| e.to_string())
}

const LIGHT: &str = "[[light]]\ntype = \"point\"\nposition = [0.5, 0.5, 0.5]\nintensity = 10\n";

#[test]
fn compiled_scene_holds_only_the_kinds_it_uses() {
    let planes = scene::load(Path::new("data/sobolev.toml"))
        .unwrap()
        .summary();
    assert!(!planes.bvh && !planes.sh && planes.planes == 2);
    assert_eq!(planes.meshes + planes.sh_objects + planes.boxes, 0);
    let text = planes.to_string();
    assert!(text.contains("BVH: none (not needed)") && text.contains("SH: none (not needed)"));

    let office = scene::load(Path::new("data/office.toml"))
        .unwrap()
        .summary();
    assert!(office.bvh && !office.sh, "{office}");
    assert_eq!(
        (office.boxes, office.rects, office.discs, office.meshes),
        (4, 2, 1, 1)
    );

    let sh = parse(&format!(
        "[[surface]]\ntype = \"sh\"\ncenter = [0.5, 0.5, 0.5]\ncoefficients = [[0, 0, 2.0, 0.0], [2, 1, 0.1, 0.05]]\n\
         sides = \"inside\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n{LIGHT}"
    ))
    .unwrap()
    .summary();
    assert!(sh.sh && !sh.bvh && sh.sh_objects == 1, "{sh}");
}

#[test]
fn every_shape_parses_and_bad_values_name_line_and_field() {
    let ok = format!(
        r#"[[surface]]
type = "rectangle"
corner = [0, 0, 0]
edge1 = [1, 0, 0]
edge2 = [0, 1, 0]
sides = "both"
material = {{ type = "lambertian", reflectance = 0.5 }}

[[surface]]
type = "disc"
center = [0, 0, 2]
normal = [0, 0, -1]
radius = 0.5
material = {{ type = "lambertian", reflectance = 0.5 }}

[[surface]]
type = "sphere"
center = [3, 3, 3]
radius = 0.5
sides = "outside"
material = {{ type = "phong", diffuse = 0.3, specular = 0.2, exponent = 10 }}

[[surface]]
type = "box"
min = [-5, -5, -5]
max = [5, 5, 5]
material = {{ type = "lambertian", reflectance = 0.5 }}
faces = {{ z_min = {{ type = "lambertian", reflectance = 0.1 }} }}
{LIGHT}"#
    );
    let s = parse(&ok).unwrap();
    assert_eq!(s.surfaces.len(), 3 + 6);
    assert_eq!(s.surfaces[7].name, "surface #4.z_min");

    let cases: [(&str, &str, &str); 8] = [
        (
            "type = \"rectangle\"\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [2, 0, 0]\n",
            "test.toml:5",
            "edge2",
        ),
        (
            "type = \"disc\"\ncenter = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = -1\n",
            "test.toml:5",
            "radius",
        ),
        (
            "type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nsides = \"around\"\n",
            "test.toml:5",
            "sides",
        ),
        (
            "type = \"box\"\nmin = [0, 0, 0]\nmax = [1, -1, 1]\n",
            "test.toml:4",
            "max",
        ),
        (
            "type = \"rectangle\"\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nradius = 2\n",
            "test.toml:6",
            "radius",
        ),
        (
            "type = \"mesh\"\nfile = \"no_such_file.obj\"\n",
            "test.toml:3",
            "no_such_file.obj",
        ),
        (
            "type = \"sh\"\ncenter = [0, 0, 0]\ncoefficients = [[0, 0, 1.0, 0.0], [1, 0, 2.0, 0.0]]\n",
            "test.toml:4",
            "star",
        ),
        ("type = \"cone\"\n", "test.toml:2", "this version knows"),
    ];
    for (body, at, what) in cases {
        let text = format!(
            "[[surface]]\n{body}material = {{ type = \"lambertian\", reflectance = 0.5 }}\n{LIGHT}"
        );
        let e = parse(&text).unwrap_err();
        assert!(e.contains(at) && e.contains(what), "{body}: {e}");
    }
    // Sphere lights are allowed among finite shapes (their partial
    // occlusion is sampled); one that cuts a plane is still refused.
    parse(
        "[[surface]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 5\nsides = \"inside\"\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0.1\nintensity = 1\n",
    )
    .unwrap();
    let e = parse(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"sphere\"\ncenter = [0, 0, 0.05]\nradius = 0.1\nintensity = 1\n",
    )
    .unwrap_err();
    assert!(e.contains("radius") && e.contains("cuts plane"), "{e}");
}

#[test]
fn inline_degree_zero_sh_sphere_gives_the_analytic_spheres_answers() {
    let body = |shape: &str| {
        format!(
            "[[surface]]\n{shape}\nsides = \"inside\"\n\
             material = {{ type = \"lambertian\", reflectance = 0.8 }}\n\
             [[light]]\ntype = \"point\"\nposition = [0.3, 0.1, -0.2]\nintensity = 10\n"
        )
    };
    let sphere = parse(&body("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1.5")).unwrap();
    let sh = parse(&body(
        "type = \"sh\"\ncenter = [0, 0, 0]\ncoefficients = [[0, 0, 1.5, 0]]",
    ))
    .unwrap();
    let pts: Vec<Receiver> = [DVec3::X, DVec3::new(0.0, 0.6, 0.8), -DVec3::Z]
        .iter()
        .map(|&u| Receiver::illuminance(u * 1.5, -u))
        .collect();
    let cfg = RunConfig {
        stop: Stop {
            chains: Some(4096),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let go = |s: &lumest::scene::Scene| {
        let rec = Receivers::from_receivers(s, &pts).unwrap();
        run(s, &rec, &cfg, &mut |_| true)
    };
    let (a, b) = (go(&sphere), go(&sh));
    // The integrating sphere's exact answer: the point light's direct
    // illuminance I cos / d^2, plus the uniform reflected part
    // rho Phi / (A (1 - rho)), Phi = 4 pi I, A = 4 pi R^2.
    let (i, rho, radius) = (10.0, 0.8, 1.5);
    let light = DVec3::new(0.3, 0.1, -0.2);
    let reflected = rho * 4.0 * std::f64::consts::PI * i
        / (4.0 * std::f64::consts::PI * radius * radius * (1.0 - rho));
    let bound = lumest::tally::sidak_bound(1e-3, pts.len(), Some(a.tallies.batches()));
    for (j, p) in pts.iter().enumerate() {
        let d = light - p.p;
        let direct = i * p.n.dot(d) / d.length().powi(3);
        assert!((a.direct[j] - direct).abs() <= 1e-12 * direct, "point {j}");
        assert_eq!(a.direct[j], b.direct[j]);
        let w = &a.tallies.estimated[j];
        assert!(w.std_error() < 0.02 * reflected, "point {j}: {w:?}");
        let z = (w.mean() - reflected) / w.std_error();
        assert!(
            z.abs() < bound,
            "point {j}: {} +- {} vs exact {reflected} (z {z})",
            w.mean(),
            w.std_error()
        );
        // Same chains through the same sphere: equal to rounding.
        let (ea, eb) = (a.tallies.estimated[j].mean(), b.tallies.estimated[j].mean());
        assert!((ea - eb).abs() <= 1e-9 * ea, "{ea} vs {eb}");
    }
}

/// The office's first order from the independent reference
/// ([`common::direct`]): the shapes of `tests/data/office_points.toml` written out here
/// (the sculpture read from `data/blob.obj` and placed by
/// `x -> translate + scale Rz(30 deg) x` with this test's own arithmetic),
/// its six 250 cd point lights.
fn office_first_order(p: DVec3, n: DVec3) -> f64 {
    use common::direct::{Occluder, RefLight, RefResponse, first_order, read_obj, triangle_mesh};
    let bx = |lo: [f64; 3], hi: [f64; 3]| Occluder::Box {
        lo: DVec3::from(lo),
        hi: DVec3::from(hi),
    };
    let (sin, cos) = 30f64.to_radians().sin_cos();
    let place = |v: DVec3| {
        DVec3::new(0.9, 3.7, 1.42)
            + 0.16 * DVec3::new(cos * v.x - sin * v.y, sin * v.x + cos * v.y, v.z)
    };
    let sculpture: Vec<[DVec3; 3]> = read_obj(&std::fs::read_to_string("data/blob.obj").unwrap())
        .into_iter()
        .map(|t| t.map(place))
        .collect();
    let occ = [
        bx([0.0, 0.0, 0.0], [6.0, 4.0, 2.8]),
        bx([1.0, 1.0, 0.0], [2.6, 1.8, 0.75]),
        bx([3.4, 1.0, 0.0], [5.0, 1.8, 0.75]),
        bx([0.2, 3.45, 0.0], [1.6, 3.95, 1.2]),
        Occluder::Parallelogram {
            o: DVec3::new(3.0, 2.4, 0.0),
            e1: DVec3::new(0.0, 1.5, 0.0),
            e2: DVec3::new(0.0, 0.0, 1.5),
        },
        Occluder::Disc {
            c: DVec3::new(4.8, 3.1, 0.72),
            n: DVec3::Z,
            r: 0.55,
        },
        Occluder::Parallelogram {
            o: DVec3::new(5.99, 0.8, 0.9),
            e1: DVec3::new(0.0, 1.8, 0.0),
            e2: DVec3::new(0.0, 0.0, 1.2),
        },
        triangle_mesh(&sculpture),
    ];
    let lights: Vec<RefLight> = [1.0, 3.0]
        .iter()
        .flat_map(|&y| {
            [1.5, 3.0, 4.5].map(|x| RefLight::Point {
                q: DVec3::new(x, y, 2.7),
                i: 250.0,
            })
        })
        .collect();
    first_order(&lights, &occ, p, n, RefResponse::Illuminance, 0)
}

/// The office grid against a pinned reference from the independent
/// backward estimator (`tests/data/office_backward_reference.csv`; the
/// command and its error bars are in the file's header): every point's E by
/// z with both error bars (Student t at 32 batches, Sidak over the 66
/// points), with R < 2 %, every statistical check passing, and the first
/// order exact against the independent reference.
#[test]
fn office_example_matches_its_pinned_backward_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("office.csv");
    let o = lumest()
        .args([
            "illuminance",
            "--scene",
            "tests/data/office_points.toml",
            "--points",
            "data/office_grid.csv",
            "--out",
            out.to_str().unwrap(),
            "--chains",
            "20000",
            // Seed 2: with the Owen nets (`--qmc owen`, the default since
            // issue 15 item 4) seed 1 flags one point of 66 for VOV (0.29,
            // one heavy batch); over seeds 1-12 the VOV check flagged 5 of
            // 792 points with owen and 3 with shift, the same false-alarm rate.
            "--seed",
            "2",
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("BVH: built") && err.contains("uniformity U0"),
        "{err}"
    );
    let read = |text: &str| -> Vec<std::collections::HashMap<String, String>> {
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        lines
            .map(|l| {
                header
                    .iter()
                    .cloned()
                    .zip(l.split(',').map(String::from))
                    .collect()
            })
            .collect()
    };
    let rows = read(&std::fs::read_to_string(&out).unwrap());
    let pinned = read(include_str!("data/office_backward_reference.csv"));
    assert_eq!(rows.len(), 66);
    assert_eq!(pinned.len(), 66);
    // Student t at the local run's batch count (from its summary line;
    // the pinned run has far more batches).
    let batches: u64 = err
        .split(" batches of ")
        .next()
        .and_then(|t| t.rsplit(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no batch count in {err}"));
    assert!(batches >= 32, "{batches} batches");
    let bound = lumest::tally::sidak_bound(1e-3, rows.len(), Some(batches));
    let mut worst: f64 = 0.0;
    let mut shadowed = 0;
    // Points where the same run 2 % high or low would fail the bound.
    let mut would_catch = [0, 0];
    for (r, p) in rows.iter().zip(&pinned) {
        let f = |m: &std::collections::HashMap<String, String>, c: &str| -> f64 {
            m[c].parse().unwrap()
        };
        let at = DVec3::new(f(r, "x"), f(r, "y"), f(r, "z"));
        let n = DVec3::new(f(r, "nx"), f(r, "ny"), f(r, "nz"));
        assert_eq!(at, DVec3::new(f(p, "x"), f(p, "y"), f(p, "z")));
        let direct = office_first_order(at, n);
        assert!(
            (f(r, "E_direct") - direct).abs() <= 1e-9 * direct,
            "{at}: first order {} vs reference {direct}",
            f(r, "E_direct")
        );
        // Points that some luminaire does not reach directly.
        if direct < 0.999 * office_first_order_unshadowed(at, n) {
            shadowed += 1;
        }
        let (e, se) = (f(r, "E"), f(r, "E_stderr"));
        let (e_ref, se_ref) = (f(p, "E"), f(p, "E_stderr"));
        assert!(se > 0.0 && se < 0.02 * e, "{at}: E {e} +- {se}");
        assert_eq!(r["E_flag"], "ok", "{at}");
        let z = (e - e_ref) / se.hypot(se_ref);
        assert!(
            z.abs() < bound,
            "{at}: E {e} +- {se} vs pinned {e_ref} +- {se_ref} (z {z})"
        );
        worst = worst.max(z.abs());
        for (k, off) in [1.02, 0.98].into_iter().enumerate() {
            if ((off * e - e_ref) / se.hypot(se_ref)).abs() >= bound {
                would_catch[k] += 1;
            }
        }
    }
    // The test has the power to see a 2 % error either way.
    assert!(
        would_catch[0] >= 1 && would_catch[1] >= 1,
        "2 % errors caught at {would_catch:?} points only"
    );
    eprintln!(
        "office: max |z| {worst:.2} (bound {bound:.2}, {batches} batches), {shadowed} points \
         shadowed; 2 % high / low would fail at {would_catch:?} points"
    );
    assert!(shadowed >= 3, "{shadowed} shadowed points");
}

/// [`office_first_order`] with nothing in the way but the room itself.
fn office_first_order_unshadowed(p: DVec3, n: DVec3) -> f64 {
    [1.0, 3.0]
        .iter()
        .flat_map(|&y| [1.5, 3.0, 4.5].map(|x| DVec3::new(x, y, 2.7)))
        .map(|q| {
            let d = q - p;
            250.0 * n.dot(d).max(0.0) / d.length().powi(3)
        })
        .sum()
}

#[test]
fn sh_fit_writes_coefficients_and_reports_the_fit() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("blob.obj");
    // An exact degree-2 shape: the fit at degree 2 leaves only the mesh's
    // flat-facet error; at degree 1 a visible residual.
    let m = star_blob(40, 80, |t: f64, p: f64| {
        1.0 + 0.2 * (3.0 * t.cos().powi(2) - 1.0) / 2.0 + 0.1 * t.sin() * p.cos()
    })
    .unwrap();
    m.write_obj(&obj).unwrap();
    let out = dir.path().join("coeffs.csv");
    let o = lumest()
        .args([
            "sh-fit",
            obj.to_str().unwrap(),
            "--degree",
            "2",
            "--out",
            out.to_str().unwrap(),
            "--center",
            "0,0,0",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("9 coefficients") && text.contains("storage"),
        "{text}"
    );
    let c = lumest::geometry::sh::read_coefficients(&out).unwrap();
    assert_eq!(c.len(), 6, "one row per (k, m), 0 <= m <= k <= 2");
    let a = |k, mm| c.iter().find(|x| x.k == k && x.m == mm).unwrap().a;
    // Facets lie inside the smooth surface by O(h^2): compare loosely.
    assert!(
        (a(0, 0) - 1.0).abs() < 2e-3
            && (a(2, 0) - 0.2).abs() < 2e-3
            && (a(1, 1) - 0.1).abs() < 2e-3,
        "{c:?}"
    );
}

/// A mesh that is not star-shaped about the centre (a ball with a second
/// ball beside it, in one OBJ) is refused: the fit kept the first hit of
/// each ray, dropped the second ball and reported a small error measured
/// on the same first hits. A degree whose least-squares arrays exceed 4 GB
/// is refused before they are allocated (--degree 100 aborted at 50 GB).
#[test]
fn sh_fit_refuses_what_r_theta_phi_cannot_describe() {
    let dir = tempfile::tempdir().unwrap();
    let ball = star_blob(20, 40, |_: f64, _: f64| 1.0).unwrap();
    let mut text = String::new();
    for shift in [0.0, 3.0] {
        for v in ball.vertices() {
            text += &format!("v {} {} {}\n", v.x + shift, v.y, v.z);
        }
    }
    let n = ball.vertices().len();
    for k in 0..2 {
        for tri in ball.triangles() {
            let ids = tri.map(|i| i as usize + 1 + k * n);
            text += &format!("f {} {} {}\n", ids[0], ids[1], ids[2]);
        }
    }
    let obj = dir.path().join("two.obj");
    std::fs::write(&obj, text).unwrap();
    let out = dir.path().join("c.csv");
    let fit = |obj: &Path, degree: &str| {
        lumest()
            .args([
                "sh-fit",
                obj.to_str().unwrap(),
                "--degree",
                degree,
                "--center",
                "0,0,0",
            ])
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap()
    };
    let o = fit(&obj, "4");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("not star-shaped"),
        "{err}"
    );
    assert!(!out.exists());
    // One ball alone fits; at degree 100 it is refused by its size.
    let one = dir.path().join("one.obj");
    ball.write_obj(&one).unwrap();
    assert!(fit(&one, "4").status.success());
    let o = fit(&one, "100");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("GB for the least-squares fit"),
        "{err}"
    );
}

/// Directions take any length and meshes are bounded where they are
/// placed: a sun vector in metres ([-1.5e11, 0, -1e11]) and an OBJ in
/// millimetres with georeferenced coordinates, re-centred by `scale` and
/// `translate`, were refused by the coordinate bound; a mesh placed beyond
/// it still is.
#[test]
fn directions_of_any_length_and_meshes_bounded_where_placed() {
    let dir = tempfile::tempdir().unwrap();
    let sun = "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
               material = { type = \"lambertian\", reflectance = 0.5 }\n\
               [[light]]\ntype = \"distant\"\ndirection = [-1.5e11, 0, -1e11]\nilluminance = 1000\n";
    let s = scene::parse(sun, &dir.path().join("sun.toml")).unwrap();
    let d = DVec3::new(-1.5, 0.0, -1.0).normalize();
    let rec = Receivers::new(&s, &[(DVec3::ZERO, DVec3::Z)]).unwrap();
    let r = run(&s, &rec, &common::chains_cfg(256, 1, 1), &mut |_| true);
    assert!(
        (r.direct[0] - 1000.0 * -d.z).abs() < 1e-9,
        "{}",
        r.direct[0]
    );
    // A 1 m cube written in millimetres, 5.8e9 mm north.
    let mut obj = String::new();
    for k in 0..8 {
        let v = [k & 1, (k >> 1) & 1, (k >> 2) & 1].map(|b| b as f64 * 1000.0);
        obj += &format!("v {} {} {}\n", 3.5e8 + v[0], 5.8e9 + v[1], v[2]);
    }
    obj += "f 1 3 2\nf 2 3 4\nf 5 6 7\nf 6 8 7\nf 1 2 5\nf 2 6 5\n\
            f 3 7 4\nf 4 7 8\nf 1 5 3\nf 3 5 7\nf 2 4 6\nf 4 8 6\n";
    std::fs::write(dir.path().join("blk.obj"), obj).unwrap();
    let mesh = |scale: &str, translate: &str| {
        format!(
            "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[surface]]\ntype = \"mesh\"\nfile = \"blk.obj\"\nscale = {scale}\ntranslate = {translate}\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[light]]\ntype = \"point\"\nposition = [0, 0, 3]\nintensity = 100\n"
        )
    };
    scene::parse(
        &mesh("0.001", "[-350000, -5800000, 0]"),
        &dir.path().join("m.toml"),
    )
    .unwrap();
    // In metres where placed: 5.8e9 m north, beyond the bound.
    let e = scene::parse(&mesh("1", "[0, 0, 0]"), &dir.path().join("m.toml")).unwrap_err();
    assert!(e.to_string().contains("beyond +-1e8 m"), "{e}");
}

#[test]
fn overflowing_light_power_is_a_clear_error() {
    let e = parse(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"point\"\nposition = [0, 0, 1]\nintensity = 1e300\n",
    )
    .unwrap_err();
    assert!(
        e.contains("test.toml:9") && e.contains("intensity") && e.contains("out of range"),
        "{e}"
    );
}

#[test]
fn extreme_intensities_and_coordinates_are_rejected_or_scale_exactly() {
    let scene = |i: &str, z: &str| {
        format!(
            "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[surface]]\ntype = \"plane\"\npoint = [0, 0, 1]\nnormal = [0, 0, -1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[light]]\ntype = \"point\"\nposition = [0, 0, {z}]\nintensity = {i}\n"
        )
    };
    // Out of range: a clear error naming the field, never NaN later.
    for (i, z, field) in [
        ("1e77", "0.5", "intensity"),
        ("1e-70", "0.5", "intensity"),
        ("1", "1e13", "position"),
    ] {
        let e = parse(&scene(i, z)).unwrap_err();
        assert!(
            e.contains(field) && (e.contains("range") || e.contains("within")),
            "{e}"
        );
    }
    // In range: the answer scales exactly with the intensity, with no NaN
    // and the same flags.
    let run = |i: &str| {
        let s = lumest::scene::parse(&scene(i, "0.5"), std::path::Path::new("t.toml")).unwrap();
        let pts = [
            (glam::DVec3::new(0.3, 0.0, 0.0), glam::DVec3::Z),
            (glam::DVec3::new(0.0, 0.0, 0.5 - 1e-6), glam::DVec3::Z),
        ];
        let rec = lumest::estimator::Receivers::new(&s, &pts).unwrap();
        let cfg = lumest::run::RunConfig {
            stop: lumest::run::Stop {
                chains: Some(20_000),
                ..Default::default()
            },
            threads: 1,
            ..Default::default()
        };
        let r = lumest::estimator::local::run(&s, &rec, &cfg, &mut |_| true);
        (0..2)
            .map(|j| {
                let w = &r.tallies.estimated[j];
                let d = r.tallies.diagnostics(j, r.direct[j]);
                (r.direct[j] + w.mean(), w.std_error(), d.vov, d.flag())
            })
            .collect::<Vec<_>>()
    };
    let (a, b, c) = (run("1"), run("1e59"), run("1e-59"));
    for j in 0..2 {
        for (x, k) in [(&b[j], 1e59), (&c[j], 1e-59)] {
            assert!(
                (x.0 / k / a[j].0 - 1.0).abs() < 1e-12,
                "{x:?} vs {:?}",
                a[j]
            );
            assert!((x.1 / k / a[j].1 - 1.0).abs() < 1e-9, "{x:?} vs {:?}", a[j]);
            assert!(
                x.2.is_finite() && (x.2 - a[j].2).abs() < 1e-6,
                "{x:?} vs {:?}",
                a[j]
            );
            assert_eq!(x.3, a[j].3);
        }
    }
}

/// The sun's `date` must exist in the Gregorian calendar: a day past the
/// month's end is refused with the file, line and field (it used to roll
/// over silently: 2026-02-30 became 2026-03-02); leap years are every 4th
/// year except centuries not divisible by 400.
#[test]
fn impossible_sun_dates_are_refused_with_file_line_and_field() {
    let scene = |date: &str| {
        format!(
            "[[light]]\ntype = \"sun\"\nilluminance = 1000\ndate = \"{date}\"\ntime = \"12:00\"\nlatitude = 50\nlongitude = 0\n"
        )
    };
    for (date, days) in [
        ("2026-02-30", "28 days"),
        ("2025-02-29", "28 days"),
        ("2026-04-31", "30 days"),
        ("1900-02-29", "28 days"),
        ("2026-06-31", "30 days"),
        ("2026-01-32", "31 days"),
    ] {
        let e = parse(&scene(date)).unwrap_err();
        assert!(
            e.contains("test.toml:4")
                && e.contains("`date`")
                && e.contains(date)
                && e.contains(days),
            "{date}: {e}"
        );
    }
    for date in [
        "2024-02-29",
        "2000-02-29",
        "2026-02-28",
        "2026-04-30",
        "2026-12-31",
        "2026-01-31",
        "2100-12-31",
        "1800-01-01",
    ] {
        parse(&scene(date)).unwrap_or_else(|e| panic!("{date}: {e}"));
    }
    // Day 0 and month 13 stay refused as before; so are years beyond the
    // algorithm's 1800-2100 (2200 was accepted).
    for date in ["2026-02-00", "2026-13-01", "2150-06-21", "1799-12-31"] {
        let e = parse(&scene(date)).unwrap_err();
        assert!(
            e.contains("test.toml:4") && e.contains("`date`"),
            "{date}: {e}"
        );
    }
}
