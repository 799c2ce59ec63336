//! Glass panes (issue 13 item 5): a distant light through a pane against
//! the slab formula, the mirror image of a point light in a pane, and the
//! light a floor sends back to itself through a pane's reflection against
//! an independent path tracer written here.

mod common;

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::scene::{Scene, parse};
use statrs::distribution::{ContinuousCDF, Normal};
use std::f64::consts::PI;
use std::path::Path;

fn sidak(m: usize) -> f64 {
    let a = 1.0 - (1.0 - 1e-4f64).powf(1.0 / m as f64);
    Normal::new(0.0, 1.0).unwrap().inverse_cdf(1.0 - a / 2.0)
}

fn scene(src: &str) -> Scene {
    parse(src, Path::new("glazing.toml")).unwrap()
}

/// The pane's (R, T) at incidence angle `theta` by the textbook route,
/// written apart from the library: Fresnel's equations in angles (Snell's
/// law), the internal transmittance `tau` found by bisection from the
/// normal transmittance, and the internal reflections summed in closed
/// form per polarisation.
fn slab(t_n: f64, n: f64, theta: f64) -> (f64, f64) {
    slab_of(t_n, n)(theta)
}

/// [`slab`] for one glass, its internal transmittance found once.
fn slab_of(t_n: f64, n: f64) -> impl Fn(f64) -> (f64, f64) {
    let fresnel = move |th: f64| -> (f64, f64) {
        if th == 0.0 {
            let r = ((n - 1.0) / (n + 1.0)).powi(2);
            return (r, r);
        }
        let tt = (th.sin() / n).asin();
        (
            ((th - tt).sin() / (th + tt).sin()).powi(2),
            ((th - tt).tan() / (th + tt).tan()).powi(2),
        )
    };
    let pol = |r: f64, tau: f64| {
        let t = (1.0 - r).powi(2) * tau / (1.0 - (r * tau).powi(2));
        (r + r * tau * t, t)
    };
    let (r0, _) = fresnel(0.0);
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if pol(r0, mid).1 < t_n {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let tau0 = 0.5 * (lo + hi);
    move |theta: f64| {
        let tt = (theta.sin() / n).asin();
        let tau = tau0.powf(1.0 / tt.cos());
        let (rs, rp) = fresnel(theta);
        let (a, b) = (pol(rs, tau), pol(rp, tau));
        ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0)
    }
}

fn v(d: DVec3) -> String {
    format!("[{:.17e}, {:.17e}, {:.17e}]", d.x, d.y, d.z)
}

#[test]
fn the_test_slab_formula_is_the_textbook_one() {
    // Lossless pane of n = 1.5: T = 2n/(n^2+1) at normal incidence; at
    // 45 degrees one interface reflects 0.0920 (s) and 0.0085 (p).
    let (r, t) = slab(12.0 / 13.0, 1.5, 0.0);
    assert!((t - 12.0 / 13.0).abs() < 1e-9 && (r - 1.0 / 13.0).abs() < 1e-9);
    let (r, t) = slab(12.0 / 13.0, 1.5, 45f64.to_radians());
    let (rs, rp) = (0.0920, 0.00847);
    let want = |r: f64| 2.0 * r / (1.0 + r);
    assert!((r - (want(rs) + want(rp)) / 2.0).abs() < 2e-4, "{r}");
    assert!((r + t - 1.0).abs() < 1e-12);
}

/// A black floor under a horizontal pane (T_n = 0.88) lit by the sun: the
/// floor under the pane gets `E_n cos T(theta)`, beside it `E_n cos`.
/// Collimated (exact at set-up) and with the sun's 0.53 degree disc
/// (sampled through the pane: light sampling and the receiver's own rays
/// must both carry the transmittance).
#[test]
fn a_pane_transmits_the_sun_by_the_slab_formula() {
    let (t_n, n) = (0.88, 1.52);
    for (k, el) in [90.0f64, 55.0, 30.0, 12.0].into_iter().enumerate() {
        let theta = (90.0 - el).to_radians();
        let d = -DVec3::new(theta.sin(), 0.0, theta.cos());
        for diameter in [0.0, 0.53] {
            let s = scene(&format!(
                r#"
[[surface]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = {{ type = "lambertian", reflectance = 0 }}

[[surface]]
type = "rectangle"
name = "pane"
corner = [-40, -40, 2]
edge1 = [80, 0, 0]
edge2 = [0, 80, 0]
material = {{ type = "glass", transmittance = {t_n}, index = {n} }}

[[light]]
type = "distant"
direction = {}
illuminance = 1e5
angular_diameter = {diameter}
"#,
                v(d)
            ));
            // Under the pane (the sun's ray from each point meets it), and
            // one far beside it (the ray towards the sun misses the pane).
            let under = [
                (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
                (DVec3::new(-3.0, 5.0, 0.0), DVec3::Z),
                (DVec3::new(1.0, 1.0, 1.0), DVec3::new(0.6, 0.0, 0.8)),
            ];
            let beside = (DVec3::new(45.0, 0.0, 0.0), DVec3::Z);
            let mut pts = under.to_vec();
            pts.push(beside);
            let mut sc = s.clone();
            sc.fit_directional(&pts.iter().map(|p| p.0).collect::<Vec<_>>());
            let rec = Receivers::new(&sc, &pts).unwrap();
            let r = run(
                &sc,
                &rec,
                &common::chains_cfg(4096, 11 + k as u64, 2),
                &mut |_| true,
            );
            let bound = sidak(pts.len());
            for (j, &(p, nn)) in pts.iter().enumerate() {
                let cos = nn.dot(-d).max(0.0);
                // Incidence on the pane: the sun's own angle.
                let t = if j < 3 { slab(t_n, n, theta).1 } else { 1.0 };
                let want = 1e5 * cos * t;
                let est = r.direct[j] + r.tallies.estimated[j].mean();
                let se = r.tallies.estimated[j].std_error();
                if diameter == 0.0 {
                    assert!(
                        (est / want - 1.0).abs() < 1e-9,
                        "el {el} point {j} {p}: {est} vs {want}"
                    );
                } else {
                    // The disc averages cos T over 0.27 degrees: < 1e-4.
                    let z = (est - want) / se.max(1e-300);
                    assert!(
                        z.abs() < bound || (est / want - 1.0).abs() < 1e-4,
                        "el {el} disc point {j}: {est} +- {se} vs {want} (z {z})"
                    );
                    assert!(0.02 * want > bound * se, "point {j}: se {se}");
                }
            }
        }
    }
}

/// A point light beside a vertical pane (the plane x = 0, 4 x 4 m) over a
/// black floor: a receiver on the light's side gets the light straight and
/// its mirror image (from the light mirrored in x = 0) with the pane's
/// reflectance at the angle of that path, where the path meets the pane;
/// a receiver on the other side gets the light through the pane.
#[test]
fn a_point_light_and_its_mirror_image_in_a_pane() {
    let (t_n, n, i) = (0.8, 1.52, 500.0);
    let s = scene(&format!(
        r#"
[[surface]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = {{ type = "lambertian", reflectance = 0 }}

[[surface]]
type = "rectangle"
corner = [0, -2, 0.5]
edge1 = [0, 4, 0]
edge2 = [0, 0, 4]
material = {{ type = "glass", transmittance = {t_n}, index = {n} }}

[[light]]
type = "point"
position = [1, 0, 2]
intensity = {i}
"#
    ));
    let l = DVec3::new(1.0, 0.0, 2.0);
    let l_img = DVec3::new(-1.0, 0.0, 2.0);
    let pts = [
        (DVec3::new(2.0, 0.5, 0.0), DVec3::Z),
        (DVec3::new(0.5, -1.0, 1.0), DVec3::new(-0.6, 0.0, 0.8)),
        (DVec3::new(3.0, 1.0, 2.5), DVec3::new(-1.0, 0.0, 0.0)),
        // Its mirror path meets x = 0 below the pane (z < 0.5): no image.
        (DVec3::new(3.0, 0.0, 0.0), DVec3::new(-0.6, 0.0, 0.8)),
        // Behind the pane.
        (DVec3::new(-1.0, 0.3, 1.5), DVec3::X),
    ];
    let rec = Receivers::new(&s, &pts).unwrap();
    for (j, &(p, nn)) in pts.iter().enumerate() {
        let point = |src: DVec3| {
            let v = src - p;
            i * nn.dot(v).max(0.0) / v.length().powi(3)
        };
        let want = if p.x > 0.0 {
            // Where the mirror path crosses x = 0.
            let f = p.x / (p.x - l_img.x);
            let m = p + (l_img - p) * f;
            let on = m.y.abs() <= 2.0 && (0.5..=4.5).contains(&m.z);
            let theta = ((m - l).normalize().x.abs()).acos();
            point(l)
                + if on {
                    slab(t_n, n, theta).0 * point(l_img)
                } else {
                    0.0
                }
        } else {
            let dd = (l - p).normalize();
            slab(t_n, n, dd.x.abs().acos()).1 * point(l)
        };
        let got = rec.direct()[j];
        assert!(
            (got / want - 1.0).abs() < 1e-9,
            "point {j} {p}: {got} vs {want}"
        );
    }
    // The image is a real part of the answer at the first point (> 1 %).
    let p = pts[0].0;
    let direct = i * (l - p).z / (l - p).length().powi(3);
    assert!(rec.direct()[0] > 1.01 * direct);
}

/// Floor (rho = 0.7, z = 0) under a 10 x 10 m horizontal pane at z = 1, a
/// point light above the pane: the floor is lit through the glass and by
/// its own light mirrored back by the pane (again and again). The local
/// estimate (chains crossing and mirrored by the pane, image scores) is
/// compared with a backward path tracer written here that shares no
/// estimator code: from an upward-facing point, a cosine-sampled ray
/// mirrored by the pane (weight R) lands on the floor, whose illuminance
/// is estimated the same way; direct light by the slab formula.
#[test]
fn light_mirrored_back_by_a_pane_matches_an_independent_tracer() {
    // A strongly reflecting glass (index 2, tinted) so that the mirrored
    // light is several per cent of the answer.
    let (t_n, n, i, rho) = (0.6, 2.0, 1000.0, 0.7);
    let s = scene(&format!(
        r#"
[[surface]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = {{ type = "lambertian", reflectance = {rho} }}

[[surface]]
type = "rectangle"
corner = [-5, -5, 1]
edge1 = [10, 0, 0]
edge2 = [0, 10, 0]
material = {{ type = "glass", transmittance = {t_n}, index = {n} }}

[[light]]
type = "point"
position = [0, 0, 2]
intensity = {i}
"#
    ));
    let l = DVec3::new(0.0, 0.0, 2.0);
    let glass = slab_of(t_n, n);
    let inside = |q: DVec3| q.x.abs() <= 5.0 && q.y.abs() <= 5.0;
    // Direct illuminance at an upward-facing point y below the pane.
    let direct = |y: DVec3| {
        let v = l - y;
        let d = v.length();
        let cross = y + v * ((1.0 - y.z) / v.z);
        let t = if inside(cross) {
            glass((v.z / d).acos()).1
        } else {
            1.0
        };
        i * t * (v.z / d) / (d * d)
    };
    // One path's estimate of E at y (facing up, z < 1).
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut uni = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut path = |mut y: DVec3| {
        let mut total = 0.0;
        let mut w = 1.0;
        for _ in 0..40 {
            total += w * direct(y);
            let (u1, u2) = (uni(), uni());
            let (sr, phi) = (u1.sqrt(), 2.0 * PI * u2);
            let d = DVec3::new(sr * phi.cos(), sr * phi.sin(), (1.0 - u1).sqrt());
            let m = y + d * ((1.0 - y.z) / d.z);
            if !inside(m) || d.z <= 0.0 {
                break;
            }
            // Mirrored down to the floor: lands at twice the run.
            let dr = DVec3::new(d.x, d.y, -d.z);
            y = m + dr * (m.z / d.z);
            w *= glass(d.z.acos()).0 * rho;
            if w < 1e-12 {
                break;
            }
        }
        total
    };
    let pts = [
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(1.5, 0.5, 0.0), DVec3::Z),
        (DVec3::new(2.5, -2.0, 0.0), DVec3::Z),
        (DVec3::new(0.5, 0.5, 0.5), DVec3::Z),
    ];
    let paths = 400_000;
    let reference: Vec<(f64, f64)> = pts
        .iter()
        .map(|&(p, _)| {
            let (mut s1, mut s2) = (0.0, 0.0);
            for _ in 0..paths {
                let e = path(p);
                s1 += e;
                s2 += e * e;
            }
            let m = s1 / paths as f64;
            (m, ((s2 / paths as f64 - m * m) / paths as f64).sqrt())
        })
        .collect();
    let rec = Receivers::new(&s, &pts).unwrap();
    let r = run(&s, &rec, &common::chains_cfg(400_000, 5, 2), &mut |_| true);
    let bound = sidak(pts.len());
    for (j, &(want, se_ref)) in reference.iter().enumerate() {
        let est = r.direct[j] + r.tallies.estimated[j].mean();
        let se = r.tallies.estimated[j].std_error();
        let z = (est - want) / se.hypot(se_ref);
        assert!(
            z.abs() < bound,
            "point {j}: {est} +- {se} vs reference {want} +- {se_ref} (z {z:.2})"
        );
        // The mirrored light is a real share (it would fail if it vanished)
        // and the run is precise enough to see it.
        let mirrored = want - direct(pts[j].0);
        assert!(mirrored > 0.02 * want, "point {j}: {mirrored} of {want}");
        assert!(
            bound * se.hypot(se_ref) < 0.25 * mirrored,
            "point {j}: se {se}"
        );
    }
}

#[test]
fn glass_keys_and_errors() {
    let base = |mat: &str, kind: &str| {
        let shape = match kind {
            "rectangle" => "corner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]",
            "plane" => "point = [0, 0, 0]\nnormal = [0, 0, 1]",
            _ => "center = [0, 0, 0]\nradius = 1",
        };
        format!(
            "[[surface]]\ntype = \"{kind}\"\n{shape}\nmaterial = {mat}\n\
             [[light]]\ntype = \"point\"\nposition = [0, 0, 3]\nintensity = 1\n"
        )
    };
    let err = |src: String| parse(&src, Path::new("g.toml")).unwrap_err().to_string();
    let e = err(base(
        "{ type = \"glass\", transmittance = 0.95 }",
        "rectangle",
    ));
    assert!(e.contains("transmittance") && e.contains("0.9"), "{e}");
    let e = err(base("{ type = \"glass\" }", "rectangle"));
    assert!(e.contains("transmittance"), "{e}");
    let e = err(base(
        "{ type = \"glass\", transmittance = 0.8, index = 0.5 }",
        "rectangle",
    ));
    assert!(e.contains("index"), "{e}");
    let e = err(base("{ type = \"glass\", transmittance = 0.8 }", "plane"));
    assert!(e.contains("rectangle") && e.contains("disc"), "{e}");
    let e = err(base("{ type = \"glass\", transmittance = 0.8 }", "sphere"));
    assert!(e.contains("rectangle") && e.contains("disc"), "{e}");
    // A disc pane and the index's default are accepted.
    let disc = base("{ type = \"glass\", transmittance = 0.8 }", "disc")
        .replace("radius = 1", "radius = 1\nnormal = [0, 0, 1]");
    assert!(parse(&disc, Path::new("g.toml")).unwrap().has_panes());
    let e = err(base(
        "{ type = \"lambertian\", reflectance = 0.5, transmittance = 0.8 }",
        "rectangle",
    ));
    assert!(e.contains("transmittance") && e.contains("glass"), "{e}");
}
