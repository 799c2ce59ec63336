//! `lumest validate luminaires`: every light kind against references that
//! share no code with the estimators ([`crate::reference`]).
//!
//! 1. **Closed forms** of the exact direct paths: a cosine luminaire from a
//!    photometric table (`E = I0 h^2 / d^4`), a uniform rectangle on
//!    parallel and perpendicular planes (configuration factors), a uniform
//!    disc (its closed form); maximum relative error over the points.
//! 2. **Sampled direct light** (error against time, z test): the panel
//!    where a box makes it sampled (multiple importance sampling), a disc
//!    with each radial profile on and off its axis (2-D quadrature), a
//!    cosine luminaire emitting from its opening; the floor is black, so the
//!    estimate is the direct light alone.
//! 3. **Flux balance** in a closed black box: the absorbed flux equals the
//!    power of every light kind, nothing escapes.
//! 4. **Variance of the direct-light strategies** (light sampling, BRDF
//!    sampling, balance and power heuristics) on a diffuse and a glossy
//!    receiver.

use super::case::{Case, CaseArgs, run_case};
use super::flux_balance::flux_balance;
use crate::estimator::direct::{self, Strategy};
use crate::estimator::{Receiver, Receivers, Response};
use crate::sampling::Philox4x32;
use crate::sampling::warp::Frame;
use crate::scene::{Scene, parse};
use clap::Args;
use glam::DVec3;
use std::path::Path;
use std::time::Instant;

/// Arguments of `lumest validate luminaires`.
#[derive(Args, Clone, Debug)]
pub struct LuminairesArgs {
    /// Samples per strategy and receiver for the variance table.
    #[arg(long, default_value_t = 200_000, allow_negative_numbers = true)]
    pub mis_samples: u64,
    /// Chains per light kind for the flux balance.
    #[arg(long, default_value_t = 200_000, allow_negative_numbers = true)]
    pub balance_chains: u64,
    /// Independent runs for the coverage of the sampled direct light's
    /// 95 % interval (0: skip).
    #[arg(long, default_value_t = 200, allow_negative_numbers = true)]
    pub coverage_runs: u64,
    #[command(flatten)]
    pub case: CaseArgs,
}

/// A black floor.
const BLACK_FLOOR: &str = r#"
[[surface]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = { type = "lambertian", reflectance = 0.0 }
"#;

/// A box far away: it makes every area source's direct light sampled
/// rather than exact.
const FAR_BOX: &str = r#"
[[surface]]
name = "far box"
type = "box"
min = [50.0, 50.0, 0.5]
max = [51.0, 51.0, 1.0]
material = { type = "lambertian", reflectance = 0.5 }
"#;

/// The panel: 0.6 m (x) by 1.2 m (y) centred over the origin at height 3 m,
/// 1000 cd/m^2, emitting down.
const PANEL: &str = r#"
[[light]]
type = "rectangle"
corner = [-0.3, 0.6, 3.0]
edge1 = [0.6, 0.0, 0.0]
edge2 = [0.0, -1.2, 0.0]
luminance = 1000.0
"#;

fn build(src: &str, dir: &Path) -> anyhow::Result<Scene> {
    parse(src, &dir.join("luminaires.toml")).map_err(|e| anyhow::anyhow!("{e}"))
}

/// A row of the flux balance: the light kind, its power \[lm\], the absorbed
/// flux \[lm\] with its standard error, and the chains that escaped.
#[derive(Clone, Debug)]
pub struct BalanceRow {
    /// What was emitted.
    pub kind: String,
    /// Power \[lm\].
    pub power: f64,
    /// Absorbed flux \[lm\].
    pub absorbed: f64,
    /// Its standard error \[lm\].
    pub std_error: f64,
    /// Chains that left the box.
    pub escaped: u64,
}

impl BalanceRow {
    /// Whether the row balances: nothing escapes and the absorbed flux
    /// agrees with the power within `z_bound` standard errors (plus
    /// rounding, 1e-12 relative: in a black box every chain deposits its
    /// whole weight, so the error is zero).
    pub fn passes(&self, z_bound: f64) -> bool {
        let tol = z_bound * self.std_error + 1e-12 * self.power;
        self.escaped == 0 && (self.absorbed - self.power).abs() <= tol && self.power > 0.0
    }
}

/// The flux balance of every light kind in a closed black box 4 x 3 x 3 m.
pub fn balance_rows(dir: &Path, chains: u64) -> anyhow::Result<Vec<BalanceRow>> {
    let walls = r#"
[[surface]]
name = "room"
type = "box"
min = [0.0, 0.0, 0.0]
max = [4.0, 3.0, 3.0]
normals = "inward"
material = { type = "lambertian", reflectance = 0.0 }
"#;
    write_cosine_ies(dir)?;
    let lights: [(&str, &str); 9] = [
        (
            "point",
            "type = \"point\"\nposition = [2.0, 1.5, 2.0]\nflux = 1000.0",
        ),
        (
            "sphere",
            "type = \"sphere\"\ncenter = [2.0, 1.5, 1.5]\nradius = 0.4\nflux = 700.0",
        ),
        (
            "ies (point)",
            "type = \"ies\"\nfile = \"cosine.ies\"\nposition = [2.0, 1.5, 2.9]",
        ),
        (
            "ies (opening, in the ceiling)",
            "type = \"ies\"\nfile = \"cosine.ies\"\nposition = [2.0, 1.5, 3.0]\nopening = true",
        ),
        (
            "rectangle (in the ceiling)",
            "type = \"rectangle\"\ncorner = [1.7, 2.1, 3.0]\nedge1 = [0.6, 0.0, 0.0]\nedge2 = [0.0, -1.2, 0.0]\nluminance = 1000.0",
        ),
        (
            "rectangle (both sides)",
            "type = \"rectangle\"\ncorner = [1.7, 2.1, 2.0]\nedge1 = [0.6, 0.0, 0.0]\nedge2 = [0.0, -1.2, 0.0]\nluminance = 1000.0\nsides = \"both\"",
        ),
        (
            "disc (uniform, tilted)",
            "type = \"disc\"\ncenter = [2.0, 1.5, 1.0]\nnormal = [0.6, 0.0, 0.8]\nradius = 0.3\nflux = 500.0",
        ),
        (
            "disc (tent profile, both sides)",
            "type = \"disc\"\ncenter = [2.0, 1.5, 1.0]\nnormal = [0.0, 0.0, -1.0]\nradius = 0.3\nflux = 500.0\nsides = \"both\"\nprofile = { type = \"tent\", turning = 0.1 }",
        ),
        (
            "disc (hyperbolic-decreasing)",
            "type = \"disc\"\ncenter = [2.0, 1.5, 2.5]\nnormal = [0.0, 0.0, -1.0]\nradius = 0.3\nflux = 500.0\nprofile = \"hyperbolic-decreasing\"",
        ),
    ];
    let mut rows = Vec::new();
    for (kind, light) in lights {
        let scene = build(&format!("{walls}\n[[light]]\n{light}\n"), dir)?;
        let f = flux_balance(&scene, chains, 32, 1);
        rows.push(BalanceRow {
            kind: kind.to_string(),
            power: scene.total_power(),
            absorbed: f.total.mean(),
            std_error: f.total.std_error(),
            escaped: f.escaped,
        });
    }
    Ok(rows)
}

/// Write `cosine.ies` into `dir`: `I = 720 cos(gamma)` cd over 0-90 degrees
/// in 0.5 degree steps, with a 0.6 m (C0) x 1.2 m (C90) luminous opening
/// (so that, emitting from its opening, it is the panel of 1000 cd/m^2).
pub fn write_cosine_ies(dir: &Path) -> anyhow::Result<()> {
    let gammas: Vec<f64> = (0..=180).map(|k| f64::from(k) * 0.5).collect();
    let cd: Vec<String> = gammas
        .iter()
        .map(|g| format!("{:.17e}", 720.0 * g.to_radians().cos()))
        .collect();
    let text = format!(
        "IESNA:LM-63-2002\n[TEST] lumest cosine panel\nTILT=NONE\n1 -1 1 {} 1 1 2 1.2 0.6 0\n1 1 0\n{}\n0\n{}\n",
        gammas.len(),
        gammas
            .iter()
            .map(|g| g.to_string())
            .collect::<Vec<_>>()
            .join(" "),
        cd.join(" ")
    );
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join("cosine.ies"), text)?;
    Ok(())
}

/// A row of the variance table: a receiver, a strategy, the mean of the
/// estimates and their variance per sample.
#[derive(Clone, Debug)]
pub struct MisRow {
    /// Receiver.
    pub receiver: String,
    /// Strategy.
    pub strategy: Strategy,
    /// Mean [lx or cd/m^2].
    pub mean: f64,
    /// Standard error of the mean.
    pub std_error: f64,
    /// Variance per sample.
    pub variance: f64,
    /// Seconds per million samples.
    pub time_per_mega: f64,
}

/// The variance of each direct-light strategy at three receivers under
/// the panel (made sampled by a far box), over a glossy floor: a diffuse
/// point 3 m off the panel's axis, a diffuse point 0.2 m below the panel,
/// the luminance of the glossy floor (Phong `kd = 0.2`, `ks = 0.5`,
/// `n = 50`) seen near the panel's mirror direction, and the same view of a
/// near-mirror (`ks = 0.9`, `n = 5000`).
pub fn mis_rows(dir: &Path, samples: u64) -> anyhow::Result<Vec<MisRow>> {
    let glossy = r#"
[[surface]]
name = "floor"
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = { type = "phong", diffuse = 0.2, specular = 0.5, exponent = 50 }

[[surface]]
name = "far box"
type = "box"
min = [50.0, 50.0, 0.5]
max = [51.0, 51.0, 1.0]
material = { type = "lambertian", reflectance = 0.5 }
"#;
    let scene = build(&format!("{glossy}{PANEL}"), dir)?;
    let material = scene.surfaces[0].material;
    let sub = DVec3::new(1.0, 0.0, 0.0);
    let wo = (DVec3::new(2.0, 0.0, 3.0) - sub).normalize();
    let receivers = [
        (
            "diffuse, 3 m off axis",
            Receiver::illuminance(DVec3::new(3.0, 0.0, 0.0), DVec3::Z),
        ),
        (
            "diffuse, 0.2 m below",
            Receiver::illuminance(DVec3::new(0.1, 0.0, 2.8), DVec3::Z),
        ),
        (
            "glossy (Phong n = 50), luminance",
            Receiver {
                p: sub,
                n: DVec3::Z,
                response: Response::Luminance {
                    material,
                    wo: Frame::from_normal(DVec3::Z).to_local(wo),
                },
            },
        ),
        (
            "near-mirror (Phong n = 5000), luminance",
            Receiver {
                p: sub,
                n: DVec3::Z,
                response: Response::Luminance {
                    material: crate::material::Material::Phong {
                        kd: 0.0,
                        ks: 0.9,
                        n: 5000.0,
                    },
                    wo: Frame::from_normal(DVec3::Z).to_local(wo),
                },
            },
        ),
    ];
    let recs: Vec<Receiver> = receivers.iter().map(|r| r.1).collect();
    let compiled = Receivers::from_receivers(&scene, &recs).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut rows = Vec::new();
    for (j, (name, rec)) in receivers.iter().enumerate() {
        let set = compiled
            .direct_set(j)
            .ok_or_else(|| anyhow::anyhow!("internal: the panel is not sampled at {name}"))?;
        let frame = Frame::from_normal(rec.n);
        for strategy in [
            Strategy::Light,
            Strategy::Brdf,
            Strategy::Balance,
            Strategy::Power,
        ] {
            let t = Instant::now();
            let (mut sum, mut sum2) = (0.0, 0.0);
            for i in 0..samples {
                let mut rng = Philox4x32::new(0x006d_6973, i);
                let v = direct::sample(&scene, set, rec, &frame, strategy, None, &mut rng);
                sum += v;
                sum2 += v * v;
            }
            let n = samples as f64;
            let mean = sum / n;
            let variance = (sum2 / n - mean * mean).max(0.0) * n / (n - 1.0).max(1.0);
            rows.push(MisRow {
                receiver: name.to_string(),
                strategy,
                mean,
                std_error: (variance / n).sqrt(),
                variance,
                time_per_mega: t.elapsed().as_secs_f64() / n * 1e6,
            });
        }
    }
    Ok(rows)
}

/// Coverage of the 95 % interval of the sampled direct light: `runs`
/// independent runs of `chains` chains of the panel over a black floor,
/// half hidden by a box (so the direct light is sampled and is the whole
/// answer), at three points whose exact values come from quadrature over
/// the panel with the box's shadow found exactly per row (written here
/// with no estimator code). Returns (covered, total, mean z, rms z).
pub fn coverage(dir: &Path, runs: u64, chains: u64) -> anyhow::Result<(u64, u64, f64, f64)> {
    let blocker = r#"
[[surface]]
name = "blocker"
type = "box"
min = [0.2, -1.0, 1.0]
max = [1.2, 1.0, 1.1]
material = { type = "lambertian", reflectance = 0.0 }
"#;
    let scene = build(&format!("{BLACK_FLOOR}{blocker}{PANEL}"), dir)?;
    let points = [
        (DVec3::new(1.6, 0.0, 0.5), DVec3::Z),
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(2.0, -0.5, 1.5), DVec3::new(-0.6, 0.0, 0.8)),
    ];
    let (lo, hi) = (DVec3::new(0.2, -1.0, 1.0), DVec3::new(1.2, 1.0, 1.1));
    let hidden = |x: DVec3, y: DVec3| {
        let d = y - x;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for k in 0..3 {
            let (a, b) = ((lo[k] - x[k]) / d[k], (hi[k] - x[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
        t0 < t1
    };
    // The exact values: for each abscissa of the panel the hidden part of
    // its line is one interval (the box is convex), found by a scan and
    // bisection; the visible parts are integrated by Gauss-Legendre panels,
    // the abscissae by 400 Gauss-Legendre panels (the row integral is
    // continuous, with kinks where the shadow starts).
    let exact: Vec<f64> = points
        .iter()
        .map(|&(x, n)| {
            let integrand = |px: f64, py: f64| {
                let v = DVec3::new(px, py, 3.0) - x;
                let d2 = v.length_squared();
                let (cx, cy) = (n.dot(v), v.z);
                if cx > 0.0 && cy > 0.0 {
                    cx * cy / (d2 * d2)
                } else {
                    0.0
                }
            };
            let row = |px: f64| {
                let blocked = |py: f64| hidden(x, DVec3::new(px, py, 3.0));
                let scan = 400;
                let ys: Vec<f64> = (0..=scan)
                    .map(|k| -0.6 + 1.2 * k as f64 / scan as f64)
                    .collect();
                let hit: Vec<usize> = (0..=scan).filter(|&k| blocked(ys[k])).collect();
                let gl = |a: f64, b: f64| {
                    let panels = 16;
                    let h = (b - a) / panels as f64;
                    (0..panels)
                        .map(|k| {
                            crate::math::quadrature::panel(
                                &|py| integrand(px, py),
                                a + h * k as f64,
                                a + h * (k + 1) as f64,
                            )
                        })
                        .sum::<f64>()
                };
                let (Some(&first), Some(&last)) = (hit.first(), hit.last()) else {
                    return gl(-0.6, 0.6);
                };
                // Ends of the hidden interval, by bisection.
                let edge = |mut vis: f64, mut hid: f64| {
                    for _ in 0..60 {
                        let m = 0.5 * (vis + hid);
                        if blocked(m) { hid = m } else { vis = m }
                    }
                    0.5 * (vis + hid)
                };
                let a = if first == 0 {
                    -0.6
                } else {
                    edge(ys[first - 1], ys[first])
                };
                let b = if last == scan {
                    0.6
                } else {
                    edge(ys[last + 1], ys[last])
                };
                gl(-0.6, a) + gl(b, 0.6)
            };
            let panels = 400;
            let h = 0.6 / panels as f64;
            1000.0
                * (0..panels)
                    .map(|k| {
                        crate::math::quadrature::panel(
                            &row,
                            -0.3 + h * k as f64,
                            -0.3 + h * (k + 1) as f64,
                        )
                    })
                    .sum::<f64>()
        })
        .collect();
    let rec = Receivers::new(&scene, &points).map_err(|e| anyhow::anyhow!("{e}"))?;
    let (mut covered, mut total, mut zs, mut z2) = (0u64, 0u64, 0.0, 0.0);

    for run in 0..runs {
        let cfg = crate::run::RunConfig {
            seed: 1000 + run,
            threads: 0,
            stop: crate::run::Stop {
                chains: Some(chains),
                ..crate::run::Stop::default()
            },
            ..crate::run::RunConfig::default()
        };
        let r = crate::estimator::local::run(&scene, &rec, &cfg, &mut |_| true);
        for (j, &e) in exact.iter().enumerate() {
            let w = &r.tallies.estimated[j];
            let est = r.direct[j] + w.mean();
            let half = crate::tally::t_factor(0.95, w.count()) * w.std_error();
            covered += u64::from((est - e).abs() <= half);
            total += 1;
            let z = (est - e) / w.std_error();
            zs += z;
            z2 += z * z;
        }
    }
    let n = total as f64;
    Ok((covered, total, zs / n, (z2 / n).sqrt()))
}

/// A closed-form check: the exact direct light of the estimator's path
/// against an independent closed form at `points` receivers.
#[derive(Clone, Debug)]
pub struct ClosedFormRow {
    /// What is checked.
    pub case: String,
    /// Receivers.
    pub points: usize,
    /// Largest relative difference.
    pub max_rel: f64,
    /// Accepted relative difference.
    pub tolerance: f64,
}

/// The exact direct light that a scene of lights alone gives (Lambert's
/// contour integral, the disc's closed form, a photometric table's
/// interpolation) against [`crate::reference::area_source`] and
/// [`crate::reference::disc_profile`]: the panel on a parallel floor and a
/// perpendicular wall (superposed configuration factors), a uniform disc
/// (2-D quadrature), and a cosine luminaire from an IES table in 0.5 degree
/// steps (`I0 h^2 / d^4`; the tolerance allows bilinear interpolation).
pub fn closed_form_rows(dir: &Path) -> anyhow::Result<Vec<ClosedFormRow>> {
    use crate::reference::area_source::{
        cosine_intensity_plane, parallel_rectangle, perpendicular_rectangle,
    };
    use crate::reference::disc_profile::disc_illuminance;
    let rel = |a: f64, b: f64| {
        if b == 0.0 {
            a.abs()
        } else {
            (a / b - 1.0).abs()
        }
    };
    let mut rows = Vec::new();
    // The panel (x in [-0.3, 0.3], y in [-0.6, 0.6], z = 3, emitting down) alone.
    let panel = build(PANEL, dir)?;
    let mut floor = Vec::new();
    let mut wall = Vec::new();
    for i in 0..9 {
        for k in 0..9 {
            let (x, y) = (-2.0 + 0.5 * i as f64, -2.0 + 0.5 * k as f64);
            floor.push((DVec3::new(x, y, 0.2 * k as f64), DVec3::Z));
            // A wall x = 1 facing -x, points below the panel's height.
            wall.push((DVec3::new(1.0, y, 0.3 * i as f64), -DVec3::X));
        }
    }
    for (name, pts, perpendicular) in [
        ("floor (parallel)", floor, false),
        ("wall (perpendicular)", wall, true),
    ] {
        let rec = Receivers::new(&panel, &pts).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut max_rel: f64 = 0.0;
        for (j, &(p, _)) in pts.iter().enumerate() {
            let exact = if perpendicular {
                // The panel's plane (z = 3) is perpendicular to the wall
                // (x = 1), at distance 3 - z from the point; the panel spans
                // y - p.y along the wall and 1 - x in [0.7, 1.3] away from it.
                perpendicular_rectangle(1000.0, -0.6 - p.y, 0.6 - p.y, 0.7, 1.3, 3.0 - p.z)
            } else {
                parallel_rectangle(
                    1000.0,
                    -0.3 - p.x,
                    0.3 - p.x,
                    -0.6 - p.y,
                    0.6 - p.y,
                    3.0 - p.z,
                )
            };
            max_rel = crate::tally::zcheck::max_abs(max_rel, rel(rec.direct()[j], exact));
        }
        rows.push(ClosedFormRow {
            case: format!("panel on a {name}: contour integral vs configuration factors"),
            points: pts.len(),
            max_rel,
            tolerance: 1e-10,
        });
    }
    // A uniform disc alone.
    let disc = build(
        "[[light]]\ntype = \"disc\"\ncenter = [0.0, 0.0, 2.5]\nnormal = [0.0, 0.0, -1.0]\nradius = 0.4\nluminance = 1000.0\n",
        dir,
    )?;
    let pts: Vec<(DVec3, DVec3)> = (0..40)
        .map(|k| {
            let t = k as f64 / 40.0;
            let n = DVec3::new((7.0 * t).sin() * 0.6, (5.0 * t).cos() * 0.3, 1.0).normalize();
            (DVec3::new(3.0 * t - 1.5, 1.0 - 2.0 * t, 2.3 * t), n)
        })
        .collect();
    let rec = Receivers::new(&disc, &pts).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut max_rel: f64 = 0.0;
    for (j, &(p, n)) in pts.iter().enumerate() {
        let exact = disc_illuminance(
            DVec3::new(0.0, 0.0, 2.5),
            -DVec3::Z,
            0.4,
            &|_| 1000.0,
            &[],
            p,
            n,
        );
        max_rel = crate::tally::zcheck::max_abs(max_rel, rel(rec.direct()[j], exact));
    }
    rows.push(ClosedFormRow {
        case: "uniform disc, tilted receivers (some cut by the horizon): closed form vs 2-D quadrature".into(),
        points: pts.len(),
        max_rel,
        tolerance: 1e-6,
    });
    // The cosine luminaire (I0 = 720 cd) 2.5 m above the floor.
    write_cosine_ies(dir)?;
    let cos = build(
        "[[light]]\ntype = \"ies\"\nfile = \"cosine.ies\"\nposition = [0.0, 0.0, 2.5]\n",
        dir,
    )?;
    let pts: Vec<(DVec3, DVec3)> = (0..50)
        .map(|k| (DVec3::new(0.13 * k as f64, 0.05 * k as f64, 0.0), DVec3::Z))
        .collect();
    let rec = Receivers::new(&cos, &pts).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut max_rel: f64 = 0.0;
    for (j, &(p, _)) in pts.iter().enumerate() {
        let d = (DVec3::new(0.0, 0.0, 2.5) - p).length();
        max_rel = crate::tally::zcheck::max_abs(
            max_rel,
            rel(rec.direct()[j], cosine_intensity_plane(720.0, 2.5, d)),
        );
    }
    rows.push(ClosedFormRow {
        case: "cosine luminaire (IES table, 0.5 deg steps): bilinear table vs I0 h^2 / d^4".into(),
        points: pts.len(),
        max_rel,
        // Linear interpolation of cos over 0.5 degrees: (dgamma^2 / 8) tan^2... at most ~1e-4 near 80 deg.
        tolerance: 2e-4,
    });
    Ok(rows)
}

/// Run `lumest validate luminaires`.
pub fn validate_luminaires(a: &LuminairesArgs) -> anyhow::Result<()> {
    let dir = a.case.report.join("luminaires_scenes");
    std::fs::create_dir_all(&dir)?;
    let mut pass = true;

    println!("## Closed forms of the exact direct light");
    for r in closed_form_rows(&dir)? {
        let ok = r.max_rel <= r.tolerance;
        pass &= ok;
        println!(
            "{:<96} {:>4} points, max rel. difference {:.2e} (tolerance {:.0e}): {}",
            r.case,
            r.points,
            r.max_rel,
            r.tolerance,
            if ok { "PASS" } else { "FAIL" }
        );
    }

    println!("\n## Direct light from the panel: variance of the sampling strategies");
    println!(
        "{:<40} {:<8} {:>14} {:>10} {:>12} {:>10} {:>10}",
        "receiver", "strategy", "mean", "std err", "var/sample", "rel. var", "s/1e6"
    );
    let rows = mis_rows(&dir, a.mis_samples)?;
    for r in &rows {
        let rel = r.variance / (r.mean * r.mean);
        println!(
            "{:<40} {:<8} {:>14.6} {:>10.2e} {:>12.4e} {:>10.4e} {:>10.3}",
            r.receiver,
            format!("{:?}", r.strategy),
            r.mean,
            r.std_error,
            r.variance,
            rel,
            r.time_per_mega
        );
    }
    // Every strategy estimates the same integral: each against the most
    // precise of its receiver's, NaN-safe (a NaN mean or error fails), at
    // a Sidak bound over all the comparisons (alpha 0.01, normal: the
    // strategies' means are over many samples). The fixed 4.5 passed a
    // NaN (`NaN > 4.5` is false) and was not derived from the count (a
    // reviewer's find).
    let bound = crate::tally::sidak_bound(0.01, rows.len(), None);
    for chunk in rows.chunks(4) {
        let best = chunk
            .iter()
            .min_by(|x, y| x.std_error.total_cmp(&y.std_error))
            .expect("four strategies");
        for r in chunk {
            let se = (r.std_error.powi(2) + best.std_error.powi(2)).sqrt();
            let z = crate::tally::zcheck::z_of_difference(r.mean - best.mean, se);
            if !crate::tally::zcheck::within(z, bound) {
                println!(
                    "strategies disagree at {}: {:?} z = {z:.2}",
                    r.receiver, r.strategy
                );
                pass = false;
            }
        }
    }

    let (runs, chains) = (a.coverage_runs, 16_384);
    if runs > 0 {
        let (covered, total, mean_z, rms_z) = coverage(&dir, runs, chains)?;
        let frac = covered as f64 / total as f64;
        // Binomial: 4 standard deviations around 95 %; and no bias of the
        // z scores (their mean within 4 standard errors of 0). The balance
        // heuristic failed the second (mean z -0.13, rms 1.17 over 1200: its
        // rare BRDF hits make batch means of 8 samples skewed); the power
        // heuristic, the default, passes.
        let sd = (0.95 * 0.05 / total as f64).sqrt();
        let ok =
            (frac - 0.95).abs() <= 4.0 * sd && mean_z.abs() <= 4.0 * rms_z / (total as f64).sqrt();
        pass &= ok;
        println!(
            "\n## Coverage of the sampled direct light ({runs} runs x {chains} chains, 3 points, half hidden panel)"
        );
        println!(
            "95 % intervals covering the exact value: {covered} / {total} = {frac:.3} (mean z {mean_z:.3}, rms z {rms_z:.3}): {}",
            if ok { "PASS" } else { "FAIL" }
        );
    }

    println!("\n## Flux balance in a closed black box (absorbed = power, nothing escapes)");
    println!(
        "{:<34} {:>14} {:>14} {:>10} {:>8}  verdict",
        "light", "power [lm]", "absorbed [lm]", "std err", "escaped"
    );
    for r in balance_rows(&dir, a.balance_chains)? {
        let ok = r.passes(4.0);
        pass &= ok;
        println!(
            "{:<34} {:>14.6} {:>14.6} {:>10.2e} {:>8}  {}",
            r.kind,
            r.power,
            r.absorbed,
            r.std_error,
            r.escaped,
            if ok { "PASS" } else { "FAIL" }
        );
    }

    // The cases share the family-wise rate `--alpha`: each runs at
    // `1 - (1 - alpha)^(1/cases)` (Sidak over the cases, each Sidak over
    // its points), not at `alpha` each (8 cases: 7.7 % for 1 %).
    let all = cases(&dir)?;
    let per_case = CaseArgs {
        alpha: crate::tally::check_bounds::per_receiver_level(a.case.alpha, all.len()),
        ..a.case.clone()
    };
    for (name, title, case) in all {
        println!("\n## {title}");
        pass &= run_case(&name, &title, &case, &per_case)?;
    }
    anyhow::ensure!(pass, "validate luminaires: a check failed (see above)");
    println!("\nvalidate luminaires: every check passed");
    Ok(())
}

/// The radial profiles of the disc cases: scene value, reference name,
/// turning radius or offset \[m\] (the disc's radius is 0.4 m), and the
/// kinks of the profile for the reference's panels.
pub const DISC_PROFILES: [(&str, &str, f64); 8] = [
    ("\"uniform\"", "uniform", 0.0),
    ("\"linear-decreasing\"", "linear-decreasing", 0.0),
    ("\"linear-increasing\"", "linear-increasing", 0.0),
    ("{ type = \"v\", turning = 0.15 }", "v", 0.15),
    ("{ type = \"tent\", turning = 0.1 }", "tent", 0.1),
    ("\"hyperbolic-decreasing\"", "hyperbolic-decreasing", 0.0),
    ("\"hyperbolic-increasing\"", "hyperbolic-increasing", 0.04),
    (
        "{ type = \"hyperbolic-increasing\", offset = 0.02 }",
        "hyperbolic-increasing",
        0.02,
    ),
];

/// A disc source of radius 0.4 m at height 2.5 m facing down, with profile
/// `k` of [`DISC_PROFILES`] and a flux of 1000 lm, over a black floor with
/// a far box (so that even the uniform disc is sampled): points on the
/// axis, off it, beyond the rim, tilted and close below the disc, with
/// their exact values by [`crate::reference::disc_profile`].
pub fn disc_case(dir: &Path, k: usize) -> anyhow::Result<Case> {
    use crate::reference::disc_profile::{disc_illuminance, profile_luminance};
    let (value, name, t) = DISC_PROFILES[k];
    let src = format!(
        "{BLACK_FLOOR}{FAR_BOX}\n[[light]]\ntype = \"disc\"\ncenter = [0.0, 0.0, 2.5]\nnormal = [0.0, 0.0, -1.0]\nradius = 0.4\nflux = 1000.0\nprofile = {value}\n"
    );
    let scene = build(&src, dir)?;
    let l0 = match &scene.lights[0] {
        crate::light::Light::Area(a) => a.l0,
        _ => anyhow::bail!("internal: not an area light"),
    };
    let pts = [
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Z),
        (DVec3::new(0.0, 0.0, 2.3), DVec3::Z),
        (DVec3::new(0.3, 0.1, 1.5), DVec3::Z),
        (DVec3::new(1.5, -0.5, 0.0), DVec3::Z),
        (
            DVec3::new(0.6, 0.0, 2.2),
            DVec3::new(-1.0, 0.0, 0.3).normalize(),
        ),
        (
            DVec3::new(-0.2, 0.3, 2.0),
            DVec3::new(0.0, 0.5, 1.0).normalize(),
        ),
    ];
    let kinks = [t];
    let l = |s: f64| l0 * profile_luminance(name, 0.4, t, s).unwrap_or(f64::NAN);
    let exact = pts
        .iter()
        .map(|&(x, n)| {
            disc_illuminance(DVec3::new(0.0, 0.0, 2.5), -DVec3::Z, 0.4, &l, &kinks, x, n)
        })
        .collect();
    Ok(Case {
        scene,
        receivers: pts
            .iter()
            .map(|&(p, n)| Receiver::illuminance(p, n))
            .collect(),
        exact,
        expected_flags: Vec::new(),
    })
}

/// The sampled-direct cases with their references: the disc with each
/// radial profile.
fn cases(dir: &Path) -> anyhow::Result<Vec<(String, String, Case)>> {
    (0..DISC_PROFILES.len())
        .map(|k| {
            let (value, ..) = DISC_PROFILES[k];
            Ok((
                format!("luminaires_disc_{k}"),
                format!("Disc source, profile {value}: direct light against 2-D quadrature"),
                disc_case(dir, k)?,
            ))
        })
        .collect()
}
