//! The Sobolev case: two infinite Lambertian planes and a point source,
//! against the exact solution ([`crate::reference::Sobolev`]); `lumest
//! validate sobolev`.

use super::case::CaseArgs;
use super::report::{checkpoint, convergence, report_convergence, z_against_exact};
use crate::commands::sobolev::SobolevParams;
use crate::estimator::{Receiver, Receivers, ViewTarget, view_target};
use crate::geometry::Plane;
use crate::io::csvio::to_csv;
use crate::io::{format_number, write_atomic};
use crate::light::Light;
use crate::material::Material;
use crate::reference::{Sobolev, SobolevValue};
use crate::run::RunConfig;
use crate::scene::Scene;
use crate::tally::{sidak_bound, zcheck};
use clap::Args;
use glam::DVec3;
use rayon::prelude::*;

/// Arguments of `lumest validate sobolev`.
#[derive(Args, Clone, Debug)]
pub struct ValidateSobolevArgs {
    #[command(flatten)]
    pub params: SobolevParams,
    /// Number of points, half on each plane.
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
    pub points: usize,
    /// Number of views (luminance), half looking at each plane.
    #[arg(long, default_value_t = 50, allow_negative_numbers = true)]
    pub views: usize,
    /// Largest horizontal distance of the points (m).
    #[arg(long = "r-max", default_value_t = 3.0, allow_negative_numbers = true)]
    pub r_max: f64,
    #[command(flatten)]
    pub case: CaseArgs,
}

/// The Sobolev problem as a scene with points on both planes and exact values.
///
/// Plane 1 is `z = 0` (normal +z), the source is at `z = h1`, plane 2 is
/// `z = h1 + h2` (normal -z). Points alternate between the planes with `r`
/// evenly spaced in `[0, r_max]` on each, at azimuths spread by the golden angle.
pub struct SobolevCase {
    pub scene: Scene,
    pub points: Vec<(DVec3, DVec3)>,
    pub plane: Vec<u8>,
    pub r: Vec<f64>,
    pub exact: Vec<SobolevValue>,
}

/// Layout of item `j` of `n` spread over both planes: its plane (1 or 2,
/// alternating), its horizontal distance (evenly spaced in `[0, r_max]` on
/// each plane) and an azimuth spread by the golden angle.
fn layout(j: usize, n: usize, r_max: f64) -> (u8, f64, f64) {
    let per_plane = [n.div_ceil(2), n / 2];
    let pl = (j % 2) as u8 + 1;
    let m = per_plane[(pl - 1) as usize];
    let rk = if m > 1 {
        r_max * (j / 2) as f64 / (m - 1) as f64
    } else {
        0.0
    };
    (
        pl,
        rk,
        std::f64::consts::PI * (3.0 - 5f64.sqrt()) * j as f64,
    )
}

/// The Sobolev problem `s` as a scene: plane 1 `z = 0` (normal +z,
/// reflectance `rho1`), the point source of `I` \[cd\] at `z = h1`, plane 2
/// `z = h1 + h2` (normal -z, reflectance `rho2`).
pub fn sobolev_scene(s: &Sobolev) -> Scene {
    Scene::from_parts(
        vec![
            (
                "plane 1".into(),
                Plane::new(DVec3::ZERO, DVec3::Z),
                Material::Lambertian { rho: s.rho1 },
            ),
            (
                "plane 2".into(),
                Plane::new(DVec3::new(0.0, 0.0, s.h1 + s.h2), -DVec3::Z),
                Material::Lambertian { rho: s.rho2 },
            ),
        ],
        vec![Light::Point {
            p: DVec3::new(0.0, 0.0, s.h1),
            i: s.intensity,
        }],
    )
    .expect("a valid programmatic scene")
}

/// The point of plane `plane` (1 or 2) of [`sobolev_scene`] at horizontal
/// distance `r` \[m\] from the foot of the source and azimuth `phi` \[rad\],
/// with the plane's normal (towards the source): `(r cos phi, r sin phi, z)`
/// with `z = 0` on plane 1 and `z = h1 + h2` on plane 2.
pub fn plane_point(s: &Sobolev, plane: u8, r: f64, phi: f64) -> (DVec3, DVec3) {
    let (z, n) = if plane == 1 {
        (0.0, DVec3::Z)
    } else {
        (s.h1 + s.h2, -DVec3::Z)
    };
    (DVec3::new(r * phi.cos(), r * phi.sin(), z), n)
}

/// Build the Sobolev validation case: [`sobolev_scene`] with the points of
/// [`SobolevCase`] ([`plane_point`]) and their exact values.
pub fn sobolev_case(s: &Sobolev, n_points: usize, r_max: f64) -> SobolevCase {
    let scene = sobolev_scene(s);
    let mut points = Vec::with_capacity(n_points);
    let mut plane = Vec::with_capacity(n_points);
    let mut r = Vec::with_capacity(n_points);
    for j in 0..n_points {
        let (pl, rk, phi) = layout(j, n_points, r_max);
        points.push(plane_point(s, pl, rk, phi));
        plane.push(pl);
        r.push(rk);
    }
    let exact = plane
        .par_iter()
        .zip(r.par_iter())
        .map(|(&pl, &rk)| s.illuminance(pl, rk))
        .collect();
    SobolevCase {
        scene,
        points,
        plane,
        r,
        exact,
    }
}

/// Views of the Sobolev case with exact luminance [cd/m^2].
///
/// View `k` looks from a point of one plane at a sub-point of the other
/// plane at horizontal distance `r'` (evenly spaced in `[0, r_max]`), from a
/// horizontal offset of `0.8 H` so that the views are oblique. For
/// Lambertian planes the exact luminance is `rho_j E_j(r') / pi` on the
/// plane `j` of the sub-point.
pub fn sobolev_views(
    s: &Sobolev,
    scene: &Scene,
    n_views: usize,
    r_max: f64,
) -> (Vec<(DVec3, DVec3)>, Vec<Receiver>, Vec<f64>) {
    let h = s.h1 + s.h2;
    let mut views = Vec::with_capacity(n_views);
    let mut receivers = Vec::with_capacity(n_views);
    let mut exact = Vec::with_capacity(n_views);
    for j in 0..n_views {
        let (target_plane, rk, phi) = layout(j, n_views, r_max);
        let phi = phi + 1.0;
        let (z_t, z_o) = if target_plane == 2 {
            (h, 0.0)
        } else {
            (0.0, h)
        };
        let target = DVec3::new(rk * phi.cos(), rk * phi.sin(), z_t);
        let offset = DVec3::new((phi + 2.0).cos(), (phi + 2.0).sin(), 0.0) * 0.8 * h;
        let o = DVec3::new(target.x, target.y, z_o) + offset;
        let d = (target - o).normalize();
        let ViewTarget::Front(rec) = view_target(scene, o, d) else {
            unreachable!("a view between the planes always meets the front side of the other plane")
        };
        let rho = if target_plane == 1 { s.rho1 } else { s.rho2 };
        views.push((o, d));
        receivers.push(rec);
        exact.push(rho * s.illuminance(target_plane, rk).e / std::f64::consts::PI);
    }
    (views, receivers, exact)
}

/// Points then views of the Sobolev case as receivers, with the exact value
/// of each (E \[lx\] for points, L [cd/m^2] for views).
pub fn sobolev_receivers(
    s: &Sobolev,
    n_points: usize,
    n_views: usize,
    r_max: f64,
) -> (SobolevCase, Vec<Receiver>, Vec<f64>) {
    let case = sobolev_case(s, n_points, r_max);
    let (_, views, lum) = sobolev_views(s, &case.scene, n_views, r_max);
    let mut all: Vec<Receiver> = case
        .points
        .iter()
        .map(|&(p, n)| Receiver::illuminance(p, n))
        .collect();
    all.extend(views);
    let mut exact: Vec<f64> = case.exact.iter().map(|v| v.e).collect();
    exact.extend(lum);
    (case, all, exact)
}

/// Run `lumest validate sobolev`: illuminance at points and luminance along
/// views in one run. Fails when the final max |z| exceeds the Sidak bound.
pub fn validate_sobolev(a: &ValidateSobolevArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.points + a.views >= 1,
        "--points plus --views must be at least 1"
    );
    anyhow::ensure!(
        a.case.time > 0.0 && a.case.time.is_finite(),
        "--time must be positive"
    );
    anyhow::ensure!(
        a.r_max >= 0.0 && a.r_max.is_finite(),
        "--r-max must be >= 0"
    );
    let problem = a.params.problem()?;
    let (case, all, exact) = sobolev_receivers(&problem, a.points, a.views, a.r_max);
    let receivers =
        Receivers::from_receivers(&case.scene, &all).map_err(|e| anyhow::anyhow!("{e}"))?;
    let cfg = RunConfig::timed(a.case.seed, a.case.threads, a.case.time);
    println!(
        "Sobolev: h1={} h2={} rho1={} rho2={} I={} cd; {} points and {} views, r in [0, {}] m, {} s",
        problem.h1,
        problem.h2,
        problem.rho1,
        problem.rho2,
        problem.intensity,
        a.points,
        a.views,
        a.r_max,
        a.case.time
    );
    let np = a.points;
    let groups = [0..np, np..np + a.views];
    let (result, tables) =
        convergence(&case.scene, &receivers, &exact, &groups, &cfg, a.case.quiet);
    let names = [
        ("sobolev", "illuminance E [lx]"),
        ("sobolev_luminance", "luminance L [cd/m^2]"),
    ];
    for ((name, what), (rows, range)) in names.iter().zip(tables.iter().zip(&groups)) {
        if range.is_empty() {
            continue;
        }
        report_convergence(
            &a.case.report,
            name,
            rows,
            what,
            &format!("Sobolev problem: relative error of {what} against run time"),
        )?;
    }
    // Per-receiver comparison.
    let headers: Vec<String> = [
        "kind", "plane", "r", "exact", "estimate", "stderr", "z", "flag",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    // A flagged receiver is not a pass, whatever its z: no receiver here
    // expects a flag (a reviewer's find: the gate judged z alone).
    let mut flagged = Vec::new();
    let cells: Vec<Vec<String>> = (0..exact.len())
        .map(|j| {
            let w = &result.tallies.estimated[j];
            let e = result.direct[j] + w.mean();
            let flag = result.tallies.diagnostics(j, result.direct[j]).flag();
            if flag != "ok" {
                flagged.push(format!("receiver {j}: {flag}"));
            }
            let (kind, plane, r) = if j < np {
                ("E", case.plane[j].to_string(), format_number(case.r[j]))
            } else {
                let p = receivers.receivers()[j].p;
                (
                    "L",
                    if p.z > 0.0 { "2" } else { "1" }.to_string(),
                    format_number(p.x.hypot(p.y)),
                )
            };
            vec![
                kind.to_string(),
                plane,
                r,
                format_number(exact[j]),
                format_number(e),
                format_number(w.std_error()),
                format_number(z_against_exact(
                    e,
                    w.std_error(),
                    result.direct[j],
                    exact[j],
                )),
                flag,
            ]
        })
        .collect();
    write_atomic(
        &a.case.report.join("sobolev_points.csv").to_string_lossy(),
        &to_csv(&headers, &cells),
    )?;
    let last = result.progress();
    let fin = checkpoint(&last, &exact, 0..exact.len());
    let bound = sidak_bound(a.case.alpha, exact.len(), Some(fin.batches));
    let pass = zcheck::within(fin.max_z, bound) && super::case::none_flagged(&flagged);
    println!(
        "max |z| = {:.3} against the Sidak bound {:.3} (alpha {}, {} receivers, {} batches): {}",
        fin.max_z,
        bound,
        a.case.alpha,
        exact.len(),
        fin.batches,
        if pass { "PASS" } else { "FAIL" }
    );
    anyhow::ensure!(
        pass,
        "Monte Carlo disagrees with the exact Sobolev solution"
    );
    Ok(())
}
