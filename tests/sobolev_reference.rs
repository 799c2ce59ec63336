//! Checks of the Sobolev reference solution (`lumest::reference::sobolev`):
//! independent high-precision data, conservation, limits, asymptotics,
//! Neumann series, a real-space integral, self-convergence and the agreement
//! of the two integration paths.

use lumest::reference::{Path, QuadOptions, Settings, Sobolev};
use lumest::tally::zcheck;
use std::f64::consts::PI;

fn rel(a: f64, b: f64) -> f64 {
    if a == b { 0.0 } else { ((a - b) / b).abs() }
}

fn set(nodes: usize, refine: u32, path: Path) -> Settings {
    Settings {
        quad: QuadOptions { nodes, refine },
        path,
    }
}

// (h_i, h_j, rho_i, rho_j) of plane `plane`
fn sides(s: &Sobolev, plane: u8) -> (f64, f64, f64, f64) {
    if plane == 1 {
        (s.h1, s.h2, s.rho1, s.rho2)
    } else {
        (s.h2, s.h1, s.rho2, s.rho1)
    }
}

const CONFIGS: [(f64, f64, f64, f64); 4] = [
    (0.5, 0.5, 0.5, 0.5),
    (0.01, 1.0, 0.9, 0.9),
    (0.3, 0.7, 0.995, 0.995),
    (1.0, 0.01, 0.2, 0.8),
];

/// validation/cases/sobolev_case_A/expected.csv: 30-digit values, h1 = h2 = 0.5, rho = 0.5.
#[test]
fn case_a_csv() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/validation/cases/sobolev_case_A/expected.csv"
    );
    let text = std::fs::read_to_string(path).expect("reading sobolev_case_A/expected.csv");
    let mut rows = 0;
    let mut worst = 0f64;
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("h1"))
    {
        let v: Vec<f64> = line.split(',').map(|x| x.trim().parse().unwrap()).collect();
        let s = Sobolev::new(v[0], v[1], v[2], v[3], 1.0).unwrap();
        let (pl, r) = (v[4] as u8, v[5]);
        let e = s.illuminance(pl, r);
        let o = s.orders(pl, r, 3);
        let errs = [
            rel(e.e, v[6]),
            rel(e.e_direct, v[7]),
            rel(e.e_reflected, v[8]),
            rel(o[0], v[9]),
            rel(o[1], v[10]),
            rel(o[2], v[11]),
        ];
        for (k, err) in errs.iter().enumerate() {
            assert!(
                *err <= 1e-10,
                "plane {pl} r {r}: column {} rel err {err:e}",
                6 + k
            );
            worst = worst.max(*err);
        }
        // single-order entry point agrees with the batch
        assert!(rel(s.order(pl, r, 2), v[10]) <= 1e-10);
        rows += 1;
    }
    assert_eq!(rows, 72);
    eprintln!("case A: worst relative error {worst:e}");
    assert!(worst < 1e-12, "worst {worst:e}");
}

/// The case as data (validation/cases/sobolev_case_A/): `scene.toml` is the
/// problem of `expected.csv` (reflectances, source) and row `k` of
/// `points.csv` is the point of row `k` of `expected.csv` on its plane,
/// facing the source: the direct illuminance of the scene's light there
/// equals the table's `E_direct` (to 1e-12).
#[test]
fn case_a_files_agree() {
    let dir = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/validation/cases/sobolev_case_A"
    );
    let scene = lumest::scene::load(std::path::Path::new(&format!("{dir}/scene.toml")))
        .expect("loading scene.toml");
    let points = lumest::io::csvio::read_points(&format!("{dir}/points.csv"))
        .expect("reading points.csv")
        .points;
    let text = std::fs::read_to_string(format!("{dir}/expected.csv")).expect("expected.csv");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("h1"))
        .map(|l| l.split(',').map(|x| x.trim().parse().unwrap()).collect())
        .collect();
    assert_eq!(points.len(), rows.len());
    assert_eq!(scene.surfaces.len(), 2);
    for (k, (&(p, n), v)) in points.iter().zip(&rows).enumerate() {
        let s = Sobolev::new(v[0], v[1], v[2], v[3], 1.0).unwrap();
        for (surface, rho) in scene.surfaces.iter().zip([s.rho1, s.rho2]) {
            assert_eq!(
                surface.material,
                lumest::material::Material::Lambertian { rho },
                "row {k}"
            );
        }
        let (plane, r) = (v[4] as u8, v[5]);
        assert_eq!(
            (p, n),
            lumest::cases::sobolev::plane_point(&s, plane, r, 0.0),
            "row {k}"
        );
        let direct: f64 = scene
            .lights
            .iter()
            .map(|l| l.direct_illuminance(p, n))
            .sum();
        assert!(
            rel(direct, v[7]) <= 1e-12,
            "row {k}: {direct} against {}",
            v[7]
        );
    }
}

// ∫_0^∞ E_refl(r) 2π r dr: Gauss–Legendre on [0, H/4] and ratio-2 panels up to
// R = 2^17 H/4, plus the far-field tail 2π (g1/R + 2 c2/R²) from
// E_refl ~ g1/r³ + 4 c2/r⁴.
fn reflected_flux_numeric(s: &Sobolev, plane: u8) -> f64 {
    let (hi, hj, ri, rj) = sides(s, plane);
    let (q, hh) = (ri * rj, hi + hj);
    let g1 = s.intensity * (q * hi + rj * hj) / (1.0 - q);
    let c2 = s.intensity * hh * hh * ((q + rj / 2.0) * (1.0 - q) + q * (q + rj))
        / ((1.0 - q) * (1.0 - q));
    let gl = lumest::reference::quadrature::Rule::new(20);
    let mut ends = vec![0.0, 0.25 * hh];
    while ends.len() < 19 {
        ends.push(2.0 * ends.last().unwrap());
    }
    let mut sum = 0.0;
    for w in ends.windows(2) {
        sum += gl.integrate(w[0], w[1], |r| {
            s.illuminance(plane, r).e_reflected * 2.0 * PI * r
        });
    }
    let big = *ends.last().unwrap();
    sum + 2.0 * PI * (g1 / big + 2.0 * c2 / (big * big))
}

/// Reflected flux 2πI[(1+ρ_j)/(1−ρ1ρ2) − 1] and absorbed total 4πI.
#[test]
fn flux_balance() {
    for (h1, h2, r1, r2) in [
        (0.5, 0.5, 0.5, 0.5),
        (0.01, 1.0, 0.9, 0.9),
        (1.0, 0.01, 0.2, 0.8),
    ] {
        let i = 2.5;
        let s = Sobolev::new(h1, h2, r1, r2, i).unwrap();
        let mut phi = [0.0; 2];
        for plane in [1u8, 2] {
            let (_, _, _, rj) = sides(&s, plane);
            let exact = 2.0 * PI * i * ((1.0 + rj) / (1.0 - r1 * r2) - 1.0);
            let num = reflected_flux_numeric(&s, plane);
            assert!(
                rel(num, exact) < 1e-6,
                "{h1} {h2} {r1} {r2} plane {plane}: {num} vs {exact}"
            );
            eprintln!(
                "flux {h1} {h2} {r1} {r2} plane {plane}: rel err {:e}",
                rel(num, exact)
            );
            phi[plane as usize - 1] = 2.0 * PI * i + num;
            assert!(rel(s.flux(plane), 2.0 * PI * i + exact) < 1e-15);
        }
        let absorbed = (1.0 - r1) * phi[0] + (1.0 - r2) * phi[1];
        eprintln!("absorbed/(4πI) − 1 = {:e}", absorbed / (4.0 * PI * i) - 1.0);
        assert!(rel(absorbed, 4.0 * PI * i) < 1e-6, "absorbed {absorbed}");
    }
}

/// ρ → 0: no reflected light from a black plane; first order only if the
/// receiving plane is black; tiny ρ gives ρ_j times the order-1 shape.
#[test]
fn zero_reflectance_limits() {
    let s = Sobolev::new(0.4, 0.8, 0.7, 0.0, 1.0).unwrap();
    let both = Sobolev::new(0.4, 0.8, 0.0, 0.0, 1.0).unwrap();
    for r in [0.0, 0.3, 2.0, 50.0, 1e4] {
        assert_eq!(s.illuminance(1, r).e_reflected, 0.0);
        assert_eq!(s.orders(1, r, 4), vec![0.0; 4]);
        assert_eq!(both.illuminance(2, r).e_reflected, 0.0);
        // plane 2 sees only light reflected once by plane 1
        let e2 = s.illuminance(2, r).e_reflected;
        let o = s.orders(2, r, 3);
        assert!(rel(e2, o[0]) < 1e-14 && o[1] == 0.0 && o[2] == 0.0, "r {r}");
    }
    let eps = 1e-7;
    let tiny = Sobolev::new(0.4, 0.8, eps, eps, 1.0).unwrap();
    let unit = Sobolev::new(0.4, 0.8, 0.0, 1.0, 1.0).unwrap();
    for r in [0.0, 0.3, 2.0, 50.0] {
        let shape = unit.order(1, r, 1);
        assert!(
            rel(tiny.illuminance(1, r).e_reflected, eps * shape) < 1e-6,
            "r {r}"
        );
    }
}

/// Swapping the planes swaps the results bit for bit; a symmetric
/// configuration gives equal planes.
#[test]
fn plane_swap_symmetry() {
    let a = Sobolev::new(0.3, 0.9, 0.6, 0.2, 1.5).unwrap();
    let b = Sobolev::new(0.9, 0.3, 0.2, 0.6, 1.5).unwrap();
    let c = Sobolev::new(0.6, 0.6, 0.4, 0.4, 1.0).unwrap();
    for r in [0.0, 0.5, 7.0, 80.0, 3e3] {
        assert_eq!(a.illuminance(1, r), b.illuminance(2, r));
        assert_eq!(a.illuminance(2, r), b.illuminance(1, r));
        assert_eq!(a.orders(1, r, 4), b.orders(2, r, 4));
        assert_eq!(c.illuminance(1, r), c.illuminance(2, r));
    }
    assert_eq!(a.far_field_coefficient(1), b.far_field_coefficient(2));
}

/// r³ E → (h_i + ρ_j h_j)/(1 − ρ1ρ2), deviation ∝ 1/r; the 1/r⁴ term is 4 c2
/// with c2 the k² ln k coefficient of G.
#[test]
fn far_field_asymptote() {
    for (h1, h2, r1, r2) in CONFIGS {
        let s = Sobolev::new(h1, h2, r1, r2, 1.0).unwrap();
        for plane in [1u8, 2] {
            let (hi, hj, ri, rj) = sides(&s, plane);
            let (q, hh) = (ri * rj, hi + hj);
            let coef = s.far_field_coefficient(plane);
            // (the library forms 1 − ρ1ρ2 with one rounding; this naive form
            // carries up to 1e-16/(1 − ρ1ρ2))
            assert!(rel(coef, (hi + rj * hj) / (1.0 - q)) < 1e-13);
            let dev = |r: f64| r.powi(3) * s.illuminance(plane, r).e / coef - 1.0;
            // the 1/r regime starts at r ≫ H/(1 − ρ1ρ2) (the c2/g1 length)
            let base = 100.0 * hh / (1.0 - q).min(0.5);
            let d: Vec<f64> = [1.0, 10.0, 100.0].iter().map(|f| dev(f * base)).collect();
            for k in 0..2 {
                let ratio = d[k + 1] / d[k];
                assert!(
                    (0.08..0.12).contains(&ratio),
                    "{h1} {h2} {r1} {r2} plane {plane}: {d:?}"
                );
            }
            // second term
            let g1 = (q * hi + rj * hj) / (1.0 - q);
            let c2 =
                hh * hh * ((q + rj / 2.0) * (1.0 - q) + q * (q + rj)) / ((1.0 - q) * (1.0 - q));
            let r = 1e3 * base;
            let e = s.illuminance(plane, r).e_reflected;
            let second = r.powi(4) * (e - g1 / r.powi(3)) / (4.0 * c2);
            assert!((second - 1.0).abs() < 2e-4, "second-term ratio {second}");
        }
    }
}

/// Σ_{n ≤ N} orders = E_reflected (remainder (ρ1ρ2)^{N/2} negligible).
#[test]
fn neumann_series_sums_to_total() {
    let cases = [
        ((0.5, 0.5, 0.5, 0.5), 80u32, 1e-12),
        ((0.5, 0.5, 0.9, 0.9), 400, 1e-10),
        ((0.01, 1.0, 0.9, 0.9), 400, 1e-10),
    ];
    for ((h1, h2, r1, r2), n, tol) in cases {
        let s = Sobolev::new(h1, h2, r1, r2, 1.0).unwrap();
        for plane in [1u8, 2] {
            for r in [0.0, 0.7, 3.0, 30.0, 100.0] {
                let o = s.orders(plane, r, n);
                let sum: f64 = o.iter().rev().sum();
                let e = s.illuminance(plane, r).e_reflected;
                assert!(
                    rel(sum, e) < tol,
                    "{h1} {h2} {r1} {r2} plane {plane} r {r}: {sum} vs {e}"
                );
                eprintln!("neumann {r1} N={n} plane {plane} r {r}: {:e}", rel(sum, e));
                // orders at r = 0 decrease at least like ρ1ρ2 every two steps
                if r == 0.0 {
                    for k in 2..o.len() {
                        assert!(o[k] <= r1 * r2 * o[k - 2] * (1.0 + 1e-12));
                    }
                }
            }
        }
    }
}

/// Order 1 at r = 0 from real space:
/// E1,i(0) = ∫_0^∞ (ρ_j/π) E0_j(s) H²/(s² + H²)² 2π s ds,
/// by Gauss–Legendre in u = ln s and in closed form.
#[test]
fn order1_at_origin_real_space() {
    for (h1, h2, r1, r2) in CONFIGS {
        let i = 1.7;
        let s = Sobolev::new(h1, h2, r1, r2, i).unwrap();
        for plane in [1u8, 2] {
            let (hi, hj, _, rj) = sides(&s, plane);
            let hh = hi + hj;
            let f = |sd: f64| {
                let e0 = i * hj / (sd * sd + hj * hj).powf(1.5);
                rj / PI * e0 * hh * hh / (sd * sd + hh * hh).powi(2) * 2.0 * PI * sd
            };
            // u = ln s over [ln(1e-9 h_j), ln(1e9 H)], 400 panels of 20 nodes
            let gl = lumest::reference::quadrature::Rule::new(20);
            let (u0, u1) = ((1e-9 * hj).ln(), (1e9 * hh).ln());
            let n = 400;
            let du = (u1 - u0) / n as f64;
            let num: f64 = (0..n)
                .map(|k| {
                    gl.integrate(u0 + k as f64 * du, u0 + (k + 1) as f64 * du, |u| {
                        f(u.exp()) * u.exp()
                    })
                })
                .sum();
            // closed form with v² = s² + h_j², c² = H² − h_j²
            let c = (hh * hh - hj * hj).sqrt();
            let a = (c / hj).atan();
            let closed = 2.0
                * rj
                * i
                * hj
                * hh
                * hh
                * (1.0 / (c.powi(4) * hj) - 1.5 * a / c.powi(5) + hj / (2.0 * c.powi(4) * hh * hh));
            let ours = s.order(plane, 0.0, 1);
            // the closed form cancels (terms ~1e3 for h_i ≪ h_j): 1e-9 only
            assert!(rel(num, closed) < 1e-9, "numeric {num} closed {closed}");
            assert!(
                rel(ours, num) < 1e-12,
                "{h1} {h2} {r1} {r2} plane {plane}: {ours} vs {num}"
            );
        }
    }
}

/// Doubling nodes and halving panels changes nothing beyond 1e-12.
#[test]
fn self_convergence() {
    let fine = set(32, 2, Path::Auto);
    let mut worst = 0f64;
    for (h1, h2, r1, r2) in CONFIGS {
        let s = Sobolev::new(h1, h2, r1, r2, 1.0).unwrap();
        for plane in [1u8, 2] {
            for r in [0.0, 1e-3, 0.7, 3.0, 30.0, 100.0] {
                let a = s.illuminance(plane, r).e_reflected;
                let b = s.illuminance_with(plane, r, &fine).e_reflected;
                let oa = s.orders(plane, r, 3);
                let ob = s.orders_with(plane, r, 3, &fine);
                let e = oa
                    .iter()
                    .zip(&ob)
                    .map(|(x, y)| rel(*x, *y))
                    .fold(rel(a, b), zcheck::max_abs);
                assert!(e < 1e-12, "{h1} {h2} {r1} {r2} plane {plane} r {r}: {e:e}");
                worst = worst.max(e);
            }
        }
    }
    eprintln!("self-convergence worst {worst:e}");
}

/// The imaginary-axis contour and the real axis agree where both apply.
#[test]
fn contour_and_real_axis_agree() {
    let mut worst = (0f64, 0f64);
    let cfgs = [
        (0.5, 0.5, 0.5, 0.5),
        (0.01, 1.0, 0.9, 0.9),
        (0.3, 0.7, 0.995, 0.995),
        (1.0, 0.01, 0.2, 0.8),
        (0.5, 0.5, 0.9995, 0.9995),
        (0.5, 0.5, 0.99995, 0.99995),
        (0.5, 0.5, 0.05, 0.1),
        (0.2, 0.8, 1.0, 0.3),
    ];
    for (h1, h2, r1, r2) in cfgs {
        let s = Sobolev::new(h1, h2, r1, r2, 1.0).unwrap();
        for plane in [1u8, 2] {
            for r in [26.0, 45.0, 100.0] {
                let c = s
                    .illuminance_with(plane, r, &set(16, 1, Path::Contour))
                    .e_reflected;
                let re = s
                    .illuminance_with(plane, r, &set(16, 1, Path::Real))
                    .e_reflected;
                assert!(
                    rel(c, re) < 1e-10,
                    "{h1} {h2} {r1} {r2} plane {plane} r {r}: {c} vs {re}"
                );
                worst.0 = worst.0.max(rel(c, re));
                let oc = s.orders_with(plane, r, 4, &set(16, 1, Path::Contour));
                let or = s.orders_with(plane, r, 4, &set(16, 1, Path::Real));
                for (x, y) in oc.iter().zip(&or) {
                    assert!(rel(*x, *y) < 1e-9, "orders {x} vs {y}");
                    worst.1 = worst.1.max(rel(*x, *y));
                }
            }
        }
    }
    eprintln!(
        "contour vs real axis: worst E {:e}, orders {:e}",
        worst.0, worst.1
    );
}

#[test]
fn invalid_parameters_are_errors() {
    for (h1, h2, r1, r2, i) in [
        (0.0, 1.0, 0.5, 0.5, 1.0),
        (-1.0, 1.0, 0.5, 0.5, 1.0),
        (1.0, f64::NAN, 0.5, 0.5, 1.0),
        (1.0, 1.0, 1.1, 0.5, 1.0),
        (1.0, 1.0, 0.5, -0.1, 1.0),
        (1.0, 1.0, 1.0, 1.0, 1.0),
        (1.0, 1.0, 0.5, 0.5, f64::INFINITY),
        (1.0, 1.0, 0.5, 0.5, -2.0),
    ] {
        assert!(
            Sobolev::new(h1, h2, r1, r2, i).is_err(),
            "{h1} {h2} {r1} {r2} {i}"
        );
    }
    let zero = Sobolev::new(1.0, 1.0, 0.5, 0.5, 0.0).unwrap();
    assert_eq!(zero.illuminance(1, 0.3).e, 0.0);
}

#[test]
#[should_panic(expected = "plane")]
fn bad_plane_panics() {
    Sobolev::new(1.0, 1.0, 0.5, 0.5, 1.0)
        .unwrap()
        .illuminance(3, 0.0);
}

#[test]
#[should_panic(expected = "r = -1")]
fn negative_r_panics() {
    Sobolev::new(1.0, 1.0, 0.5, 0.5, 1.0)
        .unwrap()
        .illuminance(1, -1.0);
}

#[test]
#[should_panic(expected = "r = NaN")]
fn nan_r_panics() {
    Sobolev::new(1.0, 1.0, 0.5, 0.5, 1.0)
        .unwrap()
        .order(1, f64::NAN, 1);
}

#[test]
#[should_panic(expected = "order n must be >= 1")]
fn order_zero_panics() {
    Sobolev::new(1.0, 1.0, 0.5, 0.5, 1.0)
        .unwrap()
        .order(1, 0.0, 0);
}
