//! Near-field emission from a luminaire's luminous shape (`opening = true`
//! on a solid LM-63 shape): the luminaire has the luminance `I(w) / A_p(w)`
//! towards every direction, `A_p(w)` the shape's projected area. Checked
//! against references sharing no code with `lumest::light`: a Lambertian
//! sphere by quadrature over its cone and by the sphere light's own
//! emission, a box and a vertical cylinder with luminous sides (and top)
//! by quadrature over their faces, and an ellipsoid and a horizontal
//! elliptic cylinder with a distribution that changes with the direction
//! by quadrature over their surfaces.

mod common;

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::estimator::direct::{self, Strategy};
use lumest::sampling::Philox4x32;
use lumest::sampling::warp::Frame;
use lumest::scene::{Scene, parse};
use statrs::distribution::{ContinuousCDF, Normal};
use std::f64::consts::PI;
use std::path::Path;

/// Two-sided z bound holding a 1e-3 false-alarm rate over `m` tests (Sidak).
fn sidak(m: usize) -> f64 {
    let alpha = 1.0 - (1.0 - 1e-3f64).powf(1.0 / m as f64);
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0)
}

const I0: f64 = 100.0;

/// An LM-63-2002 file of `I0` cd in every direction with the luminous
/// dimensions `width length height` (signed, metres).
fn isotropic_ies(width: f64, length: f64, height: f64) -> String {
    let gammas: Vec<String> = (0..=36).map(|k| (k as f64 * 5.0).to_string()).collect();
    let cd = vec![format!("{I0}"); gammas.len()];
    format!(
        "IESNA:LM-63-2002\n[TEST] isotropic\nTILT=NONE\n1 -1 1 {} 1 1 2 {width} {length} {height}\n1 1 0\n{}\n0\n{}\n",
        gammas.len(),
        gammas.join(" "),
        cd.join(" ")
    )
}

/// A scene in `dir`: a floor of reflectance 0.5 (and a far box, so that no
/// direct light is taken as exact) and `light`.
fn scene_in(dir: &Path, light: &str) -> Scene {
    let src = format!(
        "[[surface]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\n\
         [[surface]]\nname = \"far\"\ntype = \"box\"\nmin = [50, 50, 0.5]\nmax = [51, 51, 1]\n\
         material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\n[[light]]\n{light}\n"
    );
    parse(&src, &dir.join("scene.toml")).unwrap()
}

/// Mean and standard error of `n` direct-light samples at receiver `j`,
/// asserted to agree with `exact` \[lx\] within `bound` standard errors and
/// to carry a standard error under 0.5 % of it (so that a 2 % error is
/// more than 4 standard errors off, beyond every bound used here).
fn sampled_matches(
    s: &Scene,
    rec: &Receivers,
    j: usize,
    (n, seed): (u64, u64),
    exact: f64,
    bound: f64,
    what: &str,
) -> (f64, f64) {
    let (m, se) = sample_mean(s, rec, j, n, seed);
    let z = (m - exact) / se;
    assert!(
        z.abs() < bound && se < 0.005 * exact,
        "{what}: sampled {m} +- {se} vs reference {exact} (z = {z:.2})"
    );
    (m, se)
}

/// Mean and standard error of `n` direct-light samples at receiver `j`.
fn sample_mean(s: &Scene, rec: &Receivers, j: usize, n: u64, seed: u64) -> (f64, f64) {
    let set = rec.direct_set(j).expect("sampled here");
    let r = &rec.receivers()[j];
    let frame = Frame::from_normal(r.n);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for i in 0..n {
        let mut rng = Philox4x32::new(seed, i);
        let v = direct::sample(s, set, r, &frame, Strategy::Balance, None, &mut rng);
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    (mean, (var / n as f64).sqrt())
}

/// Illuminance \[lx\] at `x` (unit normal `n`) from a Lambertian sphere of
/// luminance `l`, centre `c`, radius `r`: `l int_cone max(0, n . w) dw` by
/// the midpoint rule over the cone (polar angle from its axis, azimuth).
fn sphere_quadrature(x: DVec3, n: DVec3, c: DVec3, r: f64, l: f64) -> f64 {
    let d = c - x;
    let dist = d.length();
    let alpha = (r / dist).asin();
    let f = Frame::from_normal(d / dist);
    let (nt, np) = (600, 1200);
    let mut sum = 0.0;
    for i in 0..nt {
        let t = alpha * (i as f64 + 0.5) / nt as f64;
        let (st, ct) = t.sin_cos();
        for k in 0..np {
            let p = 2.0 * PI * (k as f64 + 0.5) / np as f64;
            let w = f.to_world(DVec3::new(st * p.cos(), st * p.sin(), ct));
            sum += n.dot(w).max(0.0) * st;
        }
    }
    l * sum * (alpha / nt as f64) * (2.0 * PI / np as f64)
}

#[test]
fn an_isotropic_luminaire_with_a_spherical_shape_is_the_lambertian_sphere() {
    // I0 cd everywhere from a sphere of radius 0.2 m: luminance I0 / (pi r^2)
    // everywhere on it, the sphere light of intensity I0.
    let dir = std::env::temp_dir().join(format!("lumest-shape-sphere-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("sphere.ies"), isotropic_ies(-0.4, -0.4, -0.4)).unwrap();
    let c = DVec3::new(0.0, 0.0, 3.0);
    let gonio = |opening: bool| {
        scene_in(
            &dir,
            &format!(
                "type = \"ies\"\nfile = \"sphere.ies\"\nposition = [0, 0, 3]\nopening = {opening}"
            ),
        )
    };
    let (s_shape, s_point) = (gonio(true), gonio(false));
    let l = I0 / (PI * 0.04);
    let points = [
        (DVec3::new(0.0, 0.0, 2.5), DVec3::Z),
        // The receiver's horizon cuts the sphere.
        (DVec3::new(0.5, 0.2, 2.9), DVec3::Z),
        (DVec3::new(0.35, 0.0, 3.0), -DVec3::X),
        (DVec3::new(0.1, 0.1, 3.3), -DVec3::Z),
        (DVec3::new(1.0, -0.5, 0.0), DVec3::Z),
        // Beside it, facing up: the horizon cuts most of it.
        (DVec3::new(0.3, 0.0, 3.05), DVec3::Z),
    ];
    let rec = Receivers::new(&s_shape, &points).unwrap();
    let rec_point = Receivers::new(&s_point, &points).unwrap();
    let bound = sidak(points.len());
    for (j, &(x, n)) in points.iter().enumerate() {
        let exact = sphere_quadrature(x, n, c, 0.2, l);
        assert_eq!(rec.direct()[j], 0.0, "the shape's light is sampled");
        let (m, se) = sampled_matches(
            &s_shape,
            &rec,
            j,
            (400_000, 21),
            exact,
            bound,
            &format!("point {j}"),
        );
        // A Lambertian sphere wholly above the horizon gives I cos / d^2
        // exactly, as the point; where the horizon cuts it, it does not.
        let point = rec_point.direct()[j];
        if j == 1 || j == 5 {
            assert!(
                ((m - point) / se).abs() > bound,
                "point {j}: {point} vs {m} +- {se}"
            );
        } else {
            assert!(
                ((exact - point) / point).abs() < 1e-4,
                "point {j}: {exact} vs {point}"
            );
        }
    }
    // The chains: light reflected by the floor into points facing down, the
    // luminaire 0.25 m above it, from the shape's emission and from the
    // sphere light's (its own code: a point uniform on the sphere, a
    // cosine-weighted direction).
    let low = |s: &str| s.replace("position = [0, 0, 3]", "position = [0, 0, 0.25]");
    let low_shape = scene_in(
        &dir,
        &low("type = \"ies\"\nfile = \"sphere.ies\"\nposition = [0, 0, 3]\nopening = true"),
    );
    let low_sphere = scene_in(
        &dir,
        "type = \"sphere\"\ncenter = [0, 0, 0.25]\nradius = 0.2\nintensity = 100",
    );
    let down = [
        (DVec3::new(0.3, 0.0, 0.1), -DVec3::Z),
        (DVec3::new(0.0, 0.6, 0.2), -DVec3::Z),
        (DVec3::new(1.5, 0.5, 0.5), -DVec3::Z),
    ];
    let cfg = common::chains_cfg(200_000, 23, 2);
    let run = |s: &Scene| {
        lumest::estimator::local::run(s, &Receivers::new(s, &down).unwrap(), &cfg, &mut |_| true)
    };
    let (a, b) = (run(&low_shape), run(&low_sphere));
    for j in 0..down.len() {
        let (ea, eb, se) = common::apart(&a, &b, j);
        assert!(
            ea > 0.0 && se < 0.01 * ea && ((ea - eb) / se).abs() < sidak(down.len()),
            "point {j}: shape {ea} vs sphere {eb} +- {se}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A convex solid's face for the quadrature: `point(s, t)` over the unit
/// square, its outward unit normal and the area element [m^2] there.
type Face = Box<dyn Fn(f64, f64) -> (DVec3, DVec3, f64)>;

/// The faces of a box of half-extents `h` centred on `c`.
fn box_faces(c: DVec3, h: DVec3) -> Vec<Face> {
    let mut faces: Vec<Face> = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0, 1.0] {
            let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
            faces.push(Box::new(move |s, t| {
                let mut p = [0.0; 3];
                p[axis] = sign * h[axis];
                p[i] = h[i] * (2.0 * s - 1.0);
                p[j] = h[j] * (2.0 * t - 1.0);
                let mut n = [0.0; 3];
                n[axis] = sign;
                (
                    c + DVec3::from_array(p),
                    DVec3::from_array(n),
                    4.0 * h[i] * h[j],
                )
            }));
        }
    }
    faces
}

/// The faces of a vertical cylinder of radius `r` and half-height `hz`
/// centred on `c`: the mantle, the bottom and the top.
fn cylinder_faces(c: DVec3, r: f64, hz: f64) -> Vec<Face> {
    let mut faces: Vec<Face> = vec![Box::new(move |s, t| {
        let p = 2.0 * PI * s;
        let n = DVec3::new(p.cos(), p.sin(), 0.0);
        (
            c + n * r + DVec3::Z * (hz * (2.0 * t - 1.0)),
            n,
            2.0 * PI * r * 2.0 * hz,
        )
    })];
    for sign in [-1.0, 1.0] {
        faces.push(Box::new(move |s, t| {
            // Polar: radius r sqrt(s) would be uniform; the midpoint rule
            // takes radius r s with the Jacobian.
            let (rr, p) = (r * s, 2.0 * PI * t);
            let y = c + DVec3::new(rr * p.cos(), rr * p.sin(), sign * hz);
            (y, DVec3::Z * sign, 2.0 * PI * r * rr)
        }));
    }
    faces
}

/// Illuminance \[lx\] at `x` (unit normal `n`) from a convex luminous solid
/// of luminance `lum(w)` [cd/m^2] towards every direction `w`, by the
/// midpoint rule over its faces (`m x m` cells each).
fn solid_quadrature(
    x: DVec3,
    n: DVec3,
    faces: &[Face],
    lum: &dyn Fn(DVec3) -> f64,
    m: usize,
) -> f64 {
    let mut e = 0.0;
    for face in faces {
        for i in 0..m {
            for k in 0..m {
                let (s, t) = ((i as f64 + 0.5) / m as f64, (k as f64 + 0.5) / m as f64);
                let (y, ny, da) = face(s, t);
                let v = x - y;
                let d2 = v.length_squared();
                let w = v / d2.sqrt();
                let (cy, cx) = (ny.dot(w), -n.dot(w));
                if cy > 0.0 && cx > 0.0 {
                    e += lum(w) * cy * cx / d2 * da / (m * m) as f64;
                }
            }
        }
    }
    e
}

#[test]
fn a_box_and_a_cylinder_with_luminous_sides_and_top_against_quadrature() {
    let dir = std::env::temp_dir().join(format!("lumest-shape-solids-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A box 0.6 m (C0, x) x 0.3 m (C90, y) x 0.2 m high, and a vertical
    // cylinder 0.3 m across and 0.4 m high, both centred 3 m up.
    std::fs::write(dir.join("box.ies"), isotropic_ies(0.3, 0.6, 0.2)).unwrap();
    std::fs::write(dir.join("cyl.ies"), isotropic_ies(-0.3, -0.3, 0.4)).unwrap();
    let c = DVec3::new(0.0, 0.0, 3.0);
    let (bh, (cr, chz)) = (DVec3::new(0.3, 0.15, 0.1), (0.15, 0.2));
    let box_ap = move |w: DVec3| {
        4.0 * (bh.x * bh.y * w.z.abs() + bh.y * bh.z * w.x.abs() + bh.x * bh.z * w.y.abs())
    };
    let cyl_ap = move |w: DVec3| {
        PI * cr * cr * w.z.abs() + 2.0 * cr * 2.0 * chz * (1.0 - w.z * w.z).max(0.0).sqrt()
    };
    type Case<'a> = (&'a str, Vec<Face>, &'a dyn Fn(DVec3) -> f64);
    let cases: [Case; 2] = [
        ("box.ies", box_faces(c, bh), &box_ap),
        ("cyl.ies", cylinder_faces(c, cr, chz), &cyl_ap),
    ];
    let points = [
        // Below, close to the bottom.
        (DVec3::new(0.1, 0.05, 2.75), DVec3::Z),
        // Beside, facing the side, below the top's plane.
        (DVec3::new(0.45, 0.1, 3.05), -DVec3::X),
        // Above, facing down at the top and the sides.
        (DVec3::new(0.2, 0.1, 3.4), -DVec3::Z),
        // Oblique, tilted.
        (
            DVec3::new(-0.4, 0.5, 2.6),
            DVec3::new(0.5, -0.4, 0.7).normalize(),
        ),
        // Far off (about 20 times the size): the far field, I0 cos / d^2.
        (
            DVec3::new(12.0, 6.0, 3.5),
            DVec3::new(-0.8, -0.4, -0.2).normalize(),
        ),
    ];
    let bound = sidak(2 * points.len());
    for (k, (file, faces, a_p)) in cases.iter().enumerate() {
        let gonio = |opening: bool| {
            scene_in(
                &dir,
                &format!(
                    "type = \"ies\"\nfile = \"{file}\"\nposition = [0, 0, 3]\nopening = {opening}"
                ),
            )
        };
        let (s_shape, s_point) = (gonio(true), gonio(false));
        let rec = Receivers::new(&s_shape, &points).unwrap();
        let rec_point = Receivers::new(&s_point, &points).unwrap();
        for (j, &(x, n)) in points.iter().enumerate() {
            let exact = solid_quadrature(x, n, faces, &|w| I0 / a_p(w), 300);
            let (m, se) = sampled_matches(
                &s_shape,
                &rec,
                j,
                (1_600_000, 31 + k as u64),
                exact,
                bound,
                &format!("{file} point {j}"),
            );
            let point = rec_point.direct()[j];
            if j < 4 {
                assert!(
                    ((m - point) / se).abs() > bound,
                    "{file} point {j}: {point} vs {m} +- {se}"
                );
            } else {
                // Far off the shape is the point.
                assert!(
                    ((exact - point) / point).abs() < 2e-3,
                    "{file}: {exact} vs {point}"
                );
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_chains_and_the_backward_paths_agree_beside_a_box_luminaire_near_a_floor() {
    // The light tracing emits from the box (a direction from the table, then
    // a point uniform in the area the box projects along it); the backward
    // paths' next-event estimates draw points of the box towards each
    // vertex. Their light reflected by the floor into points facing down
    // agrees. The same beside a vertical ellipse (luminous on both faces).
    let dir = std::env::temp_dir().join(format!("lumest-shape-chains-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("box.ies"), isotropic_ies(0.3, 0.6, 0.2)).unwrap();
    std::fs::write(dir.join("vertical.ies"), isotropic_ies(-0.4, 0.0, -0.3)).unwrap();
    let down = [
        (DVec3::new(0.5, 0.0, 0.15), -DVec3::Z),
        (DVec3::new(0.0, 0.4, 0.1), -DVec3::Z),
        (DVec3::new(1.2, 0.8, 0.6), -DVec3::Z),
    ];
    let bound = sidak(2 * down.len());
    for (k, file) in ["box.ies", "vertical.ies"].iter().enumerate() {
        let s = scene_in(
            &dir,
            &format!("type = \"ies\"\nfile = \"{file}\"\nposition = [0, 0, 0.3]\nopening = true"),
        );
        let rec = Receivers::new(&s, &down).unwrap();
        let seed = 41 + 2 * k as u64;
        let cfg_a = common::chains_cfg(200_000, seed, 2);
        let a = lumest::estimator::local::run(&s, &rec, &cfg_a, &mut |_| true);
        let b = lumest::backward::run(
            &s,
            &rec,
            &common::chains_cfg(40_000, seed + 1, 2),
            &mut |_| true,
        );
        for j in 0..down.len() {
            let (ea, eb, se) = common::apart(&a, &b, j);
            assert!(
                ea > 0.0 && se < 0.02 * ea && ((ea - eb) / se).abs() < bound,
                "{file} point {j}: chains {ea} vs backward {eb} +- {se}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// An LM-63-2002 file, rotationally symmetric, of `I0 (2 - gamma / 180 deg)`
/// cd (gamma from the nadir: `2 I0` down, `I0` up; linear in gamma, so the
/// table's linear interpolation is exact) with the luminous dimensions
/// `width length height` (signed, metres).
fn sloped_ies(width: f64, length: f64, height: f64) -> String {
    let gammas: Vec<f64> = (0..=36).map(|k| k as f64 * 5.0).collect();
    let cd: Vec<String> = gammas
        .iter()
        .map(|g| format!("{}", I0 * (2.0 - g / 180.0)))
        .collect();
    let gs: Vec<String> = gammas.iter().map(|g| g.to_string()).collect();
    format!(
        "IESNA:LM-63-2002\n[TEST] sloped\nTILT=NONE\n1 -1 1 {} 1 1 2 {width} {length} {height}\n1 1 0\n{}\n0\n{}\n",
        gs.len(),
        gs.join(" "),
        cd.join(" ")
    )
}

/// The intensity \[cd\] of [`sloped_ies`] towards unit direction `w` (the
/// luminaire unrotated: the nadir `-z`).
fn sloped_intensity(w: DVec3) -> f64 {
    I0 * (2.0 - (-w.z).clamp(-1.0, 1.0).acos() / PI)
}

/// The surface of an ellipsoid of semi-axes `h` centred on `c`, by polar
/// angle and azimuth: the point, the outward unit normal (the gradient of
/// `sum (p_i / h_i)^2`) and the area element per unit square [m^2].
fn ellipsoid_faces(c: DVec3, h: DVec3) -> Vec<Face> {
    vec![Box::new(move |s, t| {
        let (th, ph) = (PI * s, 2.0 * PI * t);
        let (st, ct) = th.sin_cos();
        let (sp, cp) = ph.sin_cos();
        let u = DVec3::new(st * cp, st * sp, ct);
        let d_th = h * DVec3::new(ct * cp, ct * sp, -st) * PI;
        let d_ph = h * DVec3::new(-st * sp, st * cp, 0.0) * (2.0 * PI);
        (c + h * u, (u / h).normalize(), d_th.cross(d_ph).length())
    })]
}

/// A horizontal cylinder along `x` centred on `c`, half length `a`,
/// cross-section semi-axes `b` (along `y`) and `hz` (along `z`): the mantle
/// and the two ends.
fn x_cylinder_faces(c: DVec3, a: f64, b: f64, hz: f64) -> Vec<Face> {
    let mut faces: Vec<Face> = vec![Box::new(move |s, t| {
        let p = 2.0 * PI * t;
        let (sp, cp) = p.sin_cos();
        // Outward: the gradient of (y / b)^2 + (z / hz)^2.
        let n = DVec3::new(0.0, cp / b, sp / hz).normalize();
        let da = 2.0 * a * 2.0 * PI * (b * sp).hypot(hz * cp);
        (c + DVec3::new(a * (2.0 * s - 1.0), b * cp, hz * sp), n, da)
    })];
    for sign in [-1.0, 1.0] {
        faces.push(Box::new(move |s, t| {
            let p = 2.0 * PI * t;
            let y = c + DVec3::new(sign * a, b * s * p.cos(), hz * s * p.sin());
            (y, DVec3::X * sign, 2.0 * PI * b * hz * s)
        }));
    }
    faces
}

#[test]
fn an_ellipsoid_and_a_horizontal_elliptic_cylinder_with_a_sloped_distribution_against_quadrature() {
    // Solids with unequal semi-axes (the cap's and the mantle's normals and
    // their uniform-in-projected-area maps are affine, not radial) and an
    // intensity that changes with the direction (I(w) taken at w, not at the
    // direction of the centre), against quadrature over their surfaces with
    // the luminance I(w) / A_p(w), A_p by the classic closed forms.
    let dir = std::env::temp_dir().join(format!("lumest-shape-affine-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // An ellipsoid 0.6 m (C0, x) x 0.3 m (C90, y) x 0.2 m high, and a
    // cylinder along C0 0.6 m long, its cross-section 0.3 m (y) x 0.16 m
    // (z), both centred 3 m up.
    std::fs::write(dir.join("ell.ies"), sloped_ies(-0.3, -0.6, -0.2)).unwrap();
    std::fs::write(dir.join("hcyl.ies"), sloped_ies(-0.3, 0.6, -0.16)).unwrap();
    let c = DVec3::new(0.0, 0.0, 3.0);
    let eh = DVec3::new(0.3, 0.15, 0.1);
    let (ca, cb, cc) = (0.3, 0.15, 0.08);
    let ell_lum = move |w: DVec3| {
        let ap = PI
            * (eh.y * eh.z * w.x)
                .hypot(eh.x * eh.z * w.y)
                .hypot(eh.x * eh.y * w.z);
        sloped_intensity(w) / ap
    };
    let cyl_lum = move |w: DVec3| {
        let ap = PI * cb * cc * w.x.abs() + 4.0 * ca * (cb * w.z).hypot(cc * w.y);
        sloped_intensity(w) / ap
    };
    type Case<'a> = (&'a str, Vec<Face>, &'a dyn Fn(DVec3) -> f64);
    let cases: [Case; 2] = [
        ("ell.ies", ellipsoid_faces(c, eh), &ell_lum),
        ("hcyl.ies", x_cylinder_faces(c, ca, cb, cc), &cyl_lum),
    ];
    let points = [
        // Below, close to the bottom.
        (DVec3::new(0.1, 0.05, 2.75), DVec3::Z),
        // Beside along y, facing the mantle.
        (DVec3::new(0.1, 0.35, 3.02), -DVec3::Y),
        // Beside along x, facing the end (the ellipsoid's narrow tip).
        (DVec3::new(0.5, 0.05, 2.98), -DVec3::X),
        // Above, facing down.
        (DVec3::new(-0.2, 0.1, 3.35), -DVec3::Z),
        // Oblique, tilted.
        (
            DVec3::new(-0.4, 0.5, 2.6),
            DVec3::new(0.5, -0.4, 0.7).normalize(),
        ),
    ];
    let bound = sidak(2 * points.len());
    for (k, (file, faces, lum)) in cases.iter().enumerate() {
        let gonio = |opening: bool| {
            scene_in(
                &dir,
                &format!(
                    "type = \"ies\"\nfile = \"{file}\"\nposition = [0, 0, 3]\nopening = {opening}"
                ),
            )
        };
        let (s_shape, s_point) = (gonio(true), gonio(false));
        let rec = Receivers::new(&s_shape, &points).unwrap();
        let rec_point = Receivers::new(&s_point, &points).unwrap();
        for (j, &(x, n)) in points.iter().enumerate() {
            let exact = solid_quadrature(x, n, faces, *lum, 400);
            sampled_matches(
                &s_shape,
                &rec,
                j,
                (400_000, 51 + k as u64),
                exact,
                bound,
                &format!("{file} point {j}"),
            );
            let point = rec_point.direct()[j];
            // Near the solid the point is off (5 % to 55 % here): the test
            // tells them apart. (At the oblique point, 0.8 m off, it is
            // 0.5 % and 4 % off.)
            assert!(
                j == 4 || ((exact - point) / exact).abs() > 0.05,
                "{file} point {j}: {exact} vs point {point}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_flat_opening_lights_a_receiver_in_its_own_plane_as_just_beside_it() {
    // A flat opening emits `I(w) dA / A` from every element towards every
    // direction, the horizontal included: a receiver exactly in its plane
    // gets the limit from above and from below (the model before the
    // luminous shapes gave it too), not nothing.
    let dir = std::env::temp_dir().join(format!("lumest-shape-edge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 0.6 m (C0, x) x 0.3 m (C90, y), flat, 3 m up.
    std::fs::write(dir.join("flat.ies"), isotropic_ies(0.3, 0.6, 0.0)).unwrap();
    let s = scene_in(
        &dir,
        "type = \"ies\"\nfile = \"flat.ies\"\nposition = [0, 0, 3]\nopening = true",
    );
    // The opening's own plane, facing it from beside its end, and a
    // nanometre above and below.
    let points = [
        (DVec3::new(0.5, 0.1, 3.0), -DVec3::X),
        (DVec3::new(0.5, 0.1, 3.0 + 1e-9), -DVec3::X),
        (DVec3::new(0.5, 0.1, 3.0 - 1e-9), -DVec3::X),
    ];
    let rec = Receivers::new(&s, &points).unwrap();
    // E = (I0 / A) int cos_x / t^2 dA over the opening (midpoint rule).
    let m = 600;
    let (a, b) = (0.3, 0.15);
    let mut exact = 0.0;
    for i in 0..m {
        for k in 0..m {
            let y = DVec3::new(
                a * (2.0 * (i as f64 + 0.5) / m as f64 - 1.0),
                b * (2.0 * (k as f64 + 0.5) / m as f64 - 1.0),
                3.0,
            );
            let v = points[0].0 - y;
            let t2 = v.length_squared();
            exact += I0 / (4.0 * a * b) * (v.x / t2.sqrt()) / t2 * (4.0 * a * b) / (m * m) as f64;
        }
    }
    let bound = sidak(points.len());
    for j in 0..points.len() {
        sampled_matches(
            &s,
            &rec,
            j,
            (100_000, 61),
            exact,
            bound,
            &format!("point {j}"),
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Illuminance \[lx\] at `x` (unit normal `n`) from a flat face emitting
/// `I0 dA / A` from every element `dA` towards both sides: the midpoint rule
/// over the rectangle `c + s e1 + t e2` (`s, t` in `[-1, 1]`) or, with
/// `round`, over the ellipse of semi-axis vectors `e1`, `e2` in polar
/// coordinates.
fn flat_quadrature(x: DVec3, n: DVec3, c: DVec3, e1: DVec3, e2: DVec3, round: bool) -> f64 {
    let m = 600;
    let area = if round { PI } else { 4.0 } * e1.length() * e2.length();
    let mut e = 0.0;
    for i in 0..m {
        for k in 0..m {
            let (s, t) = ((i as f64 + 0.5) / m as f64, (k as f64 + 0.5) / m as f64);
            let (y, da) = if round {
                let (r, p) = (s, 2.0 * PI * t);
                (
                    c + e1 * (r * p.cos()) + e2 * (r * p.sin()),
                    area * 2.0 * r / (m * m) as f64,
                )
            } else {
                (
                    c + e1 * (2.0 * s - 1.0) + e2 * (2.0 * t - 1.0),
                    area / (m * m) as f64,
                )
            };
            let v = y - x;
            let t2 = v.length_squared();
            let cx = n.dot(v) / t2.sqrt();
            if cx > 0.0 {
                e += I0 / area * cx / t2 * da;
            }
        }
    }
    e
}

#[test]
fn a_flat_opening_from_above_and_a_vertical_ellipse_from_both_sides_against_quadrature() {
    // The faces no other test lights from: a flat opening's upper face (its
    // file sends light upwards too) and a vertical ellipse, luminous on both
    // faces; every element emits `I0 dA / A`.
    let dir = std::env::temp_dir().join(format!("lumest-shape-flat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 0.6 m (C0, x) x 0.3 m (C90, y), flat; a vertical ellipse facing C0,
    // 0.4 m wide (y) and 0.3 m high.
    std::fs::write(dir.join("flat.ies"), isotropic_ies(0.3, 0.6, 0.0)).unwrap();
    std::fs::write(dir.join("vertical.ies"), isotropic_ies(-0.4, 0.0, -0.3)).unwrap();
    let c = DVec3::new(0.0, 0.0, 3.0);
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let cases = [
        (
            "flat.ies",
            (x * 0.3, y * 0.15, false),
            vec![
                (DVec3::new(0.1, 0.05, 3.3), -z),
                (
                    DVec3::new(0.5, -0.2, 3.1),
                    DVec3::new(-0.6, 0.3, -0.5).normalize(),
                ),
            ],
        ),
        (
            "vertical.ies",
            (y * 0.2, z * 0.15, true),
            vec![
                (DVec3::new(0.3, 0.1, 3.05), -x),
                (DVec3::new(-0.25, -0.1, 2.9), x),
                (
                    DVec3::new(0.2, 0.5, 3.0),
                    DVec3::new(-0.3, -1.0, 0.0).normalize(),
                ),
            ],
        ),
    ];
    let bound = sidak(5);
    for (k, (file, (e1, e2, round), points)) in cases.iter().enumerate() {
        let s = scene_in(
            &dir,
            &format!("type = \"ies\"\nfile = \"{file}\"\nposition = [0, 0, 3]\nopening = true"),
        );
        let rec = Receivers::new(&s, points).unwrap();
        for (j, &(p, n)) in points.iter().enumerate() {
            let exact = flat_quadrature(p, n, c, *e1, *e2, *round);
            sampled_matches(
                &s,
                &rec,
                j,
                (200_000, 71 + k as u64),
                exact,
                bound,
                &format!("{file} point {j}"),
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_luminous_solid_cut_by_the_ceiling_is_reported() {
    // A box luminaire with luminous sides (0.2 m high) whose photometric
    // centre lies in the ceiling plane has its upper half above the ceiling;
    // mounted on the ceiling (centre 0.1 m below it, its top in the ceiling's
    // plane) and hanging free it has none, nor has a flat opening in the
    // ceiling.
    let dir = std::env::temp_dir().join(format!("lumest-shape-cut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("box.ies"), isotropic_ies(0.3, 0.6, 0.2)).unwrap();
    std::fs::write(dir.join("flat.ies"), isotropic_ies(0.3, 0.6, 0.0)).unwrap();
    let with = |file: &str, z: f64| {
        let src = format!(
            "[[surface]]\nname = \"ceiling\"\ntype = \"plane\"\npoint = [0, 0, 3]\nnormal = [0, 0, -1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.8 }}\n\n\
             [[light]]\nname = \"lum\"\ntype = \"ies\"\nfile = \"{file}\"\nposition = [0, 0, {z}]\nopening = true\n"
        );
        let s = parse(&src, &dir.join("scene.toml")).unwrap();
        (
            s.luminous_shape_cut(0),
            s.notes.iter().any(|n| n.contains("WARNING: lum: about")),
        )
    };
    let (cut, warned) = with("box.ies", 3.0);
    // Half the box: its top and the upper halves of its sides.
    assert!((cut - 0.5).abs() < 0.05 && warned, "{cut}");
    assert_eq!(with("box.ies", 2.9), (0.0, false));
    assert_eq!(with("box.ies", 2.0), (0.0, false));
    assert_eq!(with("flat.ies", 3.0), (0.0, false));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_sphere_light_centred_on_a_box_top_is_reported_half_sunk() {
    // A sphere light (radius 0.2 m) whose centre lies exactly on a box's
    // top has its lower half inside the box (the centre on the face used to
    // see every point of the sphere and report none); 0.1 m up, the cap
    // below the top is a quarter of its surface (height 0.1 of 0.4); 0.2 m
    // up it stands on the box.
    let with = |z: f64| {
        let src = format!(
            "[[surface]]\ntype = \"box\"\nmin = [-5, -5, -1]\nmax = [5, 5, 0]\nnormals = \"outward\"\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\n\
             [[light]]\nname = \"ball\"\ntype = \"sphere\"\ncenter = [0.3, -0.2, {z}]\nradius = 0.2\nflux = 1000\n"
        );
        let s = parse(&src, Path::new("sunk.toml")).unwrap();
        let warned = s.notes.iter().any(|n| n.contains("WARNING: ball: about"));
        (s.luminous_shape_cut(0), warned)
    };
    let (cut, warned) = with(0.0);
    assert!((cut - 0.5).abs() < 0.01 && warned, "{cut}");
    let (cut, warned) = with(0.1);
    assert!((cut - 0.25).abs() < 0.01 && warned, "{cut}");
    assert_eq!(with(0.2), (0.0, false));
}

/// A view that meets a luminaire's luminous shape sees its luminance
/// `I(w) / A_p(w)` towards `w = -d` (it was black before: only sphere and
/// area lights were seen). References by hand: a closed box `2a x 2b x 2c`
/// projects `4 (bc |w_x| + ac |w_y| + ab |w_z|)`, an ellipsoid of
/// semi-axes `a, b, c` projects `pi sqrt(b^2 c^2 w_x^2 + a^2 c^2 w_y^2 +
/// a^2 b^2 w_z^2)`, a flat rectangle `A |w_z|`. Views that miss the
/// shape, start inside it, look away or meet a surface first see nothing
/// of it.
#[test]
fn views_see_a_luminous_shape_as_its_luminance() {
    use lumest::estimator::emitted_luminance;
    let dir = std::env::temp_dir().join(format!("lumest-shape-views-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("box.ies"), isotropic_ies(0.3, 0.6, 0.2)).unwrap();
    std::fs::write(dir.join("flat.ies"), isotropic_ies(0.3, 0.6, 0.0)).unwrap();
    std::fs::write(dir.join("egg.ies"), sloped_ies(-0.4, -0.6, -0.2)).unwrap();
    let c = DVec3::new(0.0, 0.0, 3.0);
    let light =
        |f: &str| format!("type = \"ies\"\nfile = \"{f}\"\nposition = [0, 0, 3]\nopening = true");
    let inf = f64::INFINITY;
    let toward = |o: DVec3| (c - o).normalize();
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got - want).abs() <= 1e-9 * want.abs().max(1.0),
            "{what}: {got} cd/m^2, not {want}"
        );
    };
    // The box, 0.6 m (x) x 0.3 m (y) x 0.2 m.
    let s = scene_in(&dir, &light("box.ies"));
    let (a, b, h) = (0.3, 0.15, 0.1);
    let box_ap = |w: DVec3| 4.0 * (b * h * w.x.abs() + a * h * w.y.abs() + a * b * w.z.abs());
    let below = DVec3::new(0.1, 0.05, 0.5);
    close(
        emitted_luminance(&s, below, DVec3::Z, inf),
        I0 / (4.0 * a * b),
        "box from below",
    );
    for o in [
        DVec3::new(1.0, 0.8, 2.0),
        DVec3::new(-0.9, 0.2, 3.05),
        DVec3::new(0.4, -1.1, 4.0),
    ] {
        let d = toward(o);
        close(
            emitted_luminance(&s, o, d, inf),
            I0 / box_ap(-d),
            &format!("box from {o}"),
        );
    }
    for (o, d, t_max, what) in [
        (DVec3::new(0.5, 0.0, 0.5), DVec3::Z, inf, "beside the box"),
        (c, DVec3::X, inf, "from inside the box"),
        (below, -DVec3::Z, inf, "looking away"),
        (below, DVec3::Z, 1.0, "a surface first"),
    ] {
        assert_eq!(emitted_luminance(&s, o, d, t_max), 0.0, "{what}");
    }
    // The flat opening (0.6 m x 0.3 m at z = 3): I / (A |w_z|) from either
    // side, nothing edge-on.
    let s = scene_in(&dir, &light("flat.ies"));
    let o = DVec3::new(0.7, -0.4, 2.1);
    let d = toward(o);
    close(
        emitted_luminance(&s, o, d, inf),
        I0 / (4.0 * a * b * d.z.abs()),
        "flat from below",
    );
    let o = DVec3::new(-0.6, 0.3, 3.8);
    let d = toward(o);
    close(
        emitted_luminance(&s, o, d, inf),
        I0 / (4.0 * a * b * d.z.abs()),
        "flat from above",
    );
    assert_eq!(
        emitted_luminance(&s, DVec3::new(-1.0, 0.0, 3.0), DVec3::X, inf),
        0.0,
        "edge-on"
    );
    // The ellipsoid of semi-axes 0.3 (x), 0.2 (y), 0.1 m with the sloped
    // distribution.
    let s = scene_in(&dir, &light("egg.ies"));
    let (ea, eb, ec) = (0.3, 0.2, 0.1);
    for o in [
        DVec3::new(0.7, -0.5, 2.2),
        DVec3::new(0.05, 0.1, 1.0),
        DVec3::new(-0.3, 0.9, 3.6),
    ] {
        let w = -toward(o);
        let ap = PI
            * ((eb * ec * w.x).powi(2) + (ea * ec * w.y).powi(2) + (ea * eb * w.z).powi(2)).sqrt();
        close(
            emitted_luminance(&s, o, -w, inf),
            sloped_intensity(w) / ap,
            &format!("ellipsoid from {o}"),
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A flat luminous opening flush with the ceiling it is set into (a
/// recessed downlight placed at ceiling height): a view from the room sees
/// the opening's luminance `I / (A |w_z|)`, not the ceiling behind it (the
/// old build compared the opening's entry with the ceiling's hit strictly
/// and, meeting both at the same distance, dropped the opening: a render of
/// such a ceiling showed no luminaire); from above the ceiling, whose back
/// hides it, nothing.
#[test]
fn views_see_an_opening_flush_with_its_ceiling() {
    use lumest::estimator::emitted_luminance;
    let dir = std::env::temp_dir().join(format!("lumest-flush-views-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("flat.ies"), isotropic_ies(0.3, 0.6, 0.0)).unwrap();
    let src = "[[surface]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\n\
         [[surface]]\nname = \"ceiling\"\ntype = \"plane\"\npoint = [0, 0, 3]\nnormal = [0, 0, -1]\n\
         material = { type = \"lambertian\", reflectance = 0.7 }\n\n\
         [[light]]\ntype = \"ies\"\nfile = \"flat.ies\"\nposition = [0, 0, 3]\nopening = true\n";
    let s = parse(src, &dir.join("scene.toml")).unwrap();
    let (a, b) = (0.3, 0.15);
    let c = DVec3::new(0.0, 0.0, 3.0);
    for o in [
        DVec3::new(0.01, 0.02, 1.0),
        DVec3::new(-1.0, 0.0, 1.27),
        DVec3::new(0.7, -0.4, 2.1),
    ] {
        let d = (c + DVec3::new(0.05, -0.03, 0.0) - o).normalize();
        let t = s.first_hit_from(o, d).expect("the ceiling").t;
        let want = I0 / (4.0 * a * b * d.z.abs());
        let got = emitted_luminance(&s, o, d, t);
        assert!(
            (got - want).abs() <= 1e-9 * want,
            "view from {o}: {got} cd/m^2, not {want}"
        );
    }
    let o = DVec3::new(0.3, 0.2, 4.0);
    let d = (c - o).normalize();
    let t = s.first_hit_from(o, d).expect("the ceiling's back").t;
    assert_eq!(
        emitted_luminance(&s, o, d, t),
        0.0,
        "from above the ceiling"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A point inside a luminous solid, on it, or within `LuminousShape::NEAR`
/// of its size outside is refused, naming the shape; a point a little
/// farther out is accepted. (Within 1e-6 m of a 0.5 m sphere the sampled
/// direct light read 0 with a zero error bar, `ok`, against about 4.6e3 lx:
/// drawn uniform in the projected area seen from afar, its points almost
/// never fall on the small cap the point sees; a reviewer's find.) A flat
/// opening has no inside: a point in its plane within its outline stays
/// accepted (`a_flat_opening_lights_a_receiver_in_its_own_plane_as_just_beside_it`).
#[test]
fn points_inside_or_on_a_luminous_solid_are_refused_naming_it() {
    let dir = std::env::temp_dir().join(format!("lumest-shape-inside-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A sphere 0.5 m across, a box 0.6 x 0.3 x 0.2 m and a vertical
    // cylinder 0.3 m across and 0.4 m high, each centred 3 m up.
    std::fs::write(dir.join("sphere.ies"), isotropic_ies(-0.5, -0.5, -0.5)).unwrap();
    std::fs::write(dir.join("box.ies"), isotropic_ies(0.3, 0.6, 0.2)).unwrap();
    std::fs::write(dir.join("cyl.ies"), isotropic_ies(-0.3, -0.3, 0.4)).unwrap();
    let c = DVec3::new(0.0, 0.0, 3.0);
    for (file, name, inside, near, out) in [
        (
            "sphere.ies",
            "sphere",
            vec![c, c - DVec3::Z * 0.25, c + DVec3::new(0.15, 0.15, 0.1)],
            c - DVec3::Z * (0.25 + 1e-6),
            c - DVec3::Z * (0.25 + 1e-3),
        ),
        (
            "box.ies",
            "rectangular with luminous sides",
            vec![
                c + DVec3::new(0.29, 0.14, 0.09),
                c + DVec3::new(0.3, 0.0, -0.1),
            ],
            c + DVec3::new(0.3 + 1e-6, 0.1, 0.05),
            c + DVec3::new(0.3 + 1e-3, 0.1, 0.05),
        ),
        (
            "cyl.ies",
            "vertical cylinder",
            vec![c + DVec3::new(0.1, 0.1, 0.19)],
            c - DVec3::Z * (0.2 + 1e-6),
            c + DVec3::new(0.0, 0.15 + 1e-3, 0.0),
        ),
    ] {
        let s = scene_in(
            &dir,
            &format!(
                "type = \"ies\"\nname = \"lum\"\nfile = \"{file}\"\nposition = [0, 0, 3]\nopening = true"
            ),
        );
        for p in inside.iter().chain([&near]) {
            let e = Receivers::new(&s, &[(*p, -DVec3::Z)])
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(&format!("inside or on the luminous {name}"))
                    && e.contains("of lum at (0, 0, 3) m"),
                "{file} {p}: {e}"
            );
        }
        let rec = Receivers::new(&s, &[(out, -DVec3::Z)]);
        assert!(rec.is_ok(), "{file} {out}: refused");
    }
}
