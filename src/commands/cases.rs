//! Validation cases with finite geometry: the integrating sphere, a point
//! source over a square plate, flux balance in a closed box. Each case is a
//! scene, receivers and exact values from [`crate::reference::closed_form`];
//! `lumest validate <case>` runs it with error against run time.

use super::validate::{
    convergence, print_table, report_convergence, write_report, z_against_exact,
};
use crate::chain::{ChainEnd, ChainParams, trace_ex};
use crate::estimator::{Receiver, Receivers};
use crate::geometry::sh::{ShCoeff, ShSurface};
use crate::geometry::shapes::{AaBox, Rect, Sphere};
use crate::io::csvio::to_csv;
use crate::io::{format_number, write_atomic};
use crate::light::Light;
use crate::material::Material;
use crate::reference::closed_form::{PlateCase, integrating_sphere_indirect, point_illuminance};
use crate::run::RunConfig;
use crate::sampling::Philox4x32;
use crate::scene::{Scene, Sides, SurfaceSpec};
use crate::tally::{Welford, sidak_bound, zcheck};
use clap::Args;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::path::PathBuf;

/// Run controls and report of a validation case.
#[derive(Args, Clone, Debug)]
pub struct CaseArgs {
    /// Wall-clock time of the run [s].
    #[arg(long, default_value_t = 10.0)]
    pub time: f64,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Folder for the tables (CSV) and plots (SVG).
    #[arg(long, default_value = "validation_report")]
    pub report: PathBuf,
    /// Family-wise false-alarm rate of the z test over all points.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// A scene with receivers and their exact values.
#[derive(Clone, Debug)]
pub struct Case {
    /// The scene.
    pub scene: Scene,
    /// Receivers (illuminance points).
    pub receivers: Vec<Receiver>,
    /// Exact illuminance [lx] at each receiver.
    pub exact: Vec<f64>,
}

/// `n` nearly uniform unit vectors (a Fibonacci spiral).
pub fn spiral(n: usize) -> Vec<DVec3> {
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - (2.0 * k as f64 + 1.0) / n as f64;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let (sp, cp) = (golden * k as f64).sin_cos();
            DVec3::new(s * cp, s * sp, z)
        })
        .collect()
}

/// Arguments of `lumest validate integrating-sphere`.
#[derive(Args, Clone, Debug)]
pub struct SphereArgs {
    /// Wall reflectance, in [0, 1).
    #[arg(long, default_value_t = 0.9)]
    pub rho: f64,
    /// Radius [m].
    #[arg(long, default_value_t = 1.0)]
    pub radius: f64,
    /// Source position relative to the centre, in units of the radius: `x,y,z`.
    #[arg(long, default_value = "0.3,-0.2,0.45", allow_hyphen_values = true)]
    pub source: String,
    /// Number of points on the wall.
    #[arg(long, default_value_t = 100)]
    pub points: usize,
    /// Give the sphere as a degree-0 spherical-harmonic object instead.
    #[arg(long)]
    pub sh: bool,
    #[command(flatten)]
    pub case: CaseArgs,
}

/// The integrating sphere (centre `(0.1, 0.2, 0.3) R`): points on the wall
/// facing inwards, a point source of 100 cd at `source * R` from the centre.
pub fn sphere_case(rho: f64, radius: f64, source: DVec3, n_points: usize, as_sh: bool) -> Case {
    let c = DVec3::new(0.1, 0.2, 0.3) * radius;
    let s = c + source * radius;
    let i = 100.0;
    let m = Material::Lambertian { rho };
    let spec = if as_sh {
        sh_sphere_spec(c, radius, m)
    } else {
        SurfaceSpec::Sphere("sphere".into(), Sphere { c, r: radius }, Sides::Back, m)
    };
    let scene = Scene::build(vec![spec], vec![Light::Point { p: s, i }])
        .expect("a valid programmatic scene");
    let ind = integrating_sphere_indirect(rho, 4.0 * PI * i, radius);
    let (receivers, exact) = spiral(n_points)
        .into_iter()
        .map(|u| {
            let (p, n) = (c + u * radius, -u);
            (
                Receiver::illuminance(p, n),
                point_illuminance(i, s, p, n) + ind,
            )
        })
        .unzip();
    Case {
        scene,
        receivers,
        exact,
    }
}

/// The sphere of radius `r` about `c` as a degree-0 SH object, reflecting inside.
fn sh_sphere_spec(c: DVec3, r: f64, m: Material) -> SurfaceSpec {
    let coeff = ShCoeff {
        k: 0,
        m: 0,
        a: r,
        b: 0.0,
    };
    let o =
        ShSurface::new(&[coeff], c, glam::DMat3::IDENTITY, 1.0).expect("a sphere is star-shaped");
    SurfaceSpec::Sh("sphere (SH)".into(), o, Sides::Back, m)
}

/// Arguments of `lumest validate plate`.
#[derive(Args, Clone, Debug)]
pub struct PlateArgs {
    /// Side of the square plate [m].
    #[arg(long, default_value_t = 1.0)]
    pub side: f64,
    /// Reflectance of the plate.
    #[arg(long, default_value_t = 0.8)]
    pub rho: f64,
    /// Number of points.
    #[arg(long, default_value_t = 40)]
    pub points: usize,
    #[command(flatten)]
    pub case: CaseArgs,
}

/// A point source of 100 cd at `(0.3, 0.6, 0.8) a` over the plate
/// `[0, a]^2`; half the points on the normal through the corner at heights
/// `0.05 a .. 2 a` facing the plate, the rest above the plate at scattered
/// positions and tilts (the plate wholly above their horizon), and three points under the plate
/// (direct light only: two lit past its edges, the last in its shadow).
pub fn plate_case(a: f64, rho: f64, n_points: usize) -> Case {
    let pc = PlateCase {
        a,
        rho,
        source: DVec3::new(0.3, 0.6, 0.8) * a,
        intensity: 100.0,
    };
    let rect = Rect::new(DVec3::ZERO, DVec3::X * a, DVec3::Y * a).expect("square");
    let scene = Scene::build(
        vec![SurfaceSpec::Rect(
            "plate".into(),
            rect,
            Sides::Front,
            Material::Lambertian { rho },
        )],
        vec![Light::Point {
            p: pc.source,
            i: pc.intensity,
        }],
    )
    .expect("a valid programmatic scene");
    let mut rng = Philox4x32::new(7, 0);
    let mut receivers = Vec::with_capacity(n_points);
    let n_corner = n_points / 2;
    for k in 0..n_corner {
        let h = a * (0.05 + 1.95 * k as f64 / (n_corner.max(2) - 1) as f64);
        receivers.push(Receiver::illuminance(DVec3::new(0.0, 0.0, h), -DVec3::Z));
    }
    // Rejection sampling below accepts about half the candidates; the cap
    // keeps it finite whatever happens.
    let mut tries = 0;
    while receivers.len() + 3 < n_points && tries < 1000 * n_points {
        tries += 1;
        let [u, v] = rng.next_2d();
        let [w, t] = rng.next_2d();
        let p = DVec3::new(-0.5 + 2.0 * u, -0.5 + 2.0 * v, 0.1 + 1.2 * w) * a;
        let n = DVec3::new(t - 0.5, 0.3 * (w - 0.5), -1.0).normalize();
        // Keep the plate wholly above the receiver's horizon, so that the
        // reference integrand is smooth (a horizon cut would be a kink).
        let corners = [
            DVec3::ZERO,
            DVec3::X * a,
            DVec3::Y * a,
            DVec3::new(a, a, 0.0),
        ];
        if corners
            .iter()
            .all(|&c| (c - p).dot(n) > 0.05 * (c - p).length())
        {
            receivers.push(Receiver::illuminance(p, n));
        }
    }
    // Under the plate: two lit past its edges, one in its shadow (last: exact 0).
    receivers.extend([
        Receiver::illuminance(DVec3::new(1.6, 0.3, -0.3) * a, DVec3::Z),
        Receiver::illuminance(
            DVec3::new(0.5, -0.4, -0.1) * a,
            DVec3::new(0.0, 0.3, 1.0).normalize(),
        ),
        Receiver::illuminance(DVec3::new(0.2, 0.3, -0.3) * a, DVec3::Z),
    ]);
    let exact = receivers
        .iter()
        .map(|r| {
            if r.p.z > 0.0 {
                let (d, refl) = pc.illuminance(r.p, r.n);
                d + refl
            } else {
                // Under the plate: direct light only, if the plate does not block it.
                let t = r.p.z / (r.p.z - pc.source.z);
                let x = r.p + (pc.source - r.p) * t;
                let blocked = (0.0..=a).contains(&x.x) && (0.0..=a).contains(&x.y);
                if blocked {
                    0.0
                } else {
                    point_illuminance(pc.intensity, pc.source, r.p, r.n)
                }
            }
        })
        .collect::<Vec<f64>>();
    // Receivers with exact value 0 last (see `run_case`).
    let (mut lit, mut dark): (Vec<_>, Vec<_>) = receivers
        .into_iter()
        .zip(exact)
        .partition(|(_, e)| *e != 0.0);
    lit.append(&mut dark);
    let (receivers, exact) = lit.into_iter().unzip();
    Case {
        scene,
        receivers,
        exact,
    }
}

/// Run a case with checkpoints; print the table and the z test, write the
/// report. Returns whether max |z| stays within the Sidak bound.
pub fn run_case(name: &str, title: &str, case: &Case, a: &CaseArgs) -> anyhow::Result<bool> {
    anyhow::ensure!(
        a.time > 0.0 && a.time.is_finite(),
        "--time must be positive"
    );
    let receivers = Receivers::from_receivers(&case.scene, &case.receivers)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    eprintln!("lumest: scene: {}", case.scene.summary());
    let cfg = RunConfig::timed(a.seed, a.threads, a.time);
    let n = case.exact.len();
    // Relative errors need non-zero exact values: those come first, and the
    // table covers them; every receiver enters the z test.
    let nz = case.exact.iter().take_while(|&&e| e != 0.0).count();
    anyhow::ensure!(
        case.exact[nz..].iter().all(|&e| e == 0.0),
        "internal: receivers with exact value 0 must come last"
    );
    let zeros = n - nz;
    let range = 0..nz;
    let groups = std::slice::from_ref(&range);
    let (result, tables) = convergence(&case.scene, &receivers, &case.exact, groups, &cfg, a.quiet);
    report_convergence(
        &a.report,
        name,
        &tables[0],
        title,
        &format!("{title}: relative error against run time"),
    )?;
    let headers: Vec<String> = [
        "x", "y", "z", "nx", "ny", "nz", "exact", "estimate", "stderr", "z_score",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut max_z: f64 = 0.0;
    let cells: Vec<Vec<String>> = (0..n)
        .map(|j| {
            let r = &case.receivers[j];
            let w = &result.tallies.indirect[j];
            let e = result.direct[j] + w.mean();
            let z = z_against_exact(e, w.std_error(), result.direct[j], case.exact[j]);
            max_z = zcheck::max_abs(max_z, z);
            let mut row: Vec<String> = [r.p.x, r.p.y, r.p.z, r.n.x, r.n.y, r.n.z]
                .iter()
                .map(|&v| format_number(v))
                .collect();
            row.extend(
                [case.exact[j], e, w.std_error(), z]
                    .iter()
                    .map(|&v| format_number(v)),
            );
            row
        })
        .collect();
    std::fs::create_dir_all(&a.report)?;
    write_atomic(
        &a.report
            .join(format!("{name}_points.csv"))
            .to_string_lossy(),
        &to_csv(&headers, &cells),
    )?;
    let batches = result.tallies.batches();
    let bound = sidak_bound(a.alpha, n, Some(batches));
    let pass = zcheck::within(max_z, bound);
    if zeros > 0 {
        println!("{zeros} receiver(s) with exact value 0 (checked to be estimated as exactly 0)");
    }
    println!(
        "max |z| = {max_z:.3} against the Sidak bound {bound:.3} (alpha {}, {n} receivers, {batches} batches): {}",
        a.alpha,
        if pass { "PASS" } else { "FAIL" }
    );
    Ok(pass)
}

/// Parse `x,y,z`.
fn vec3(s: &str, what: &str) -> anyhow::Result<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| anyhow::anyhow!("{what}: {e}"))?;
    anyhow::ensure!(
        v.len() == 3 && v.iter().all(|x| x.is_finite()),
        "{what}: expected three finite numbers x,y,z"
    );
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// `lumest validate integrating-sphere`.
pub fn validate_sphere(a: &SphereArgs) -> anyhow::Result<()> {
    anyhow::ensure!((0.0..1.0).contains(&a.rho), "--rho must lie in [0, 1)");
    anyhow::ensure!(
        a.radius > 0.0 && a.radius.is_finite(),
        "--radius must be positive"
    );
    let src = vec3(&a.source, "--source")?;
    anyhow::ensure!(
        src.length() < 0.999,
        "--source must lie inside the sphere (|s| < 1)"
    );
    anyhow::ensure!(a.points >= 1, "--points must be at least 1");
    let case = sphere_case(a.rho, a.radius, src, a.points, a.sh);
    println!(
        "Integrating sphere{}: R = {} m, rho = {}, 100 cd at {} R from the centre; {} wall points; exact indirect {} lx",
        if a.sh { " (degree-0 SH object)" } else { "" },
        a.radius,
        a.rho,
        src,
        a.points,
        format_number(integrating_sphere_indirect(a.rho, 400.0 * PI, a.radius))
    );
    let name = if a.sh {
        "integrating_sphere_sh"
    } else {
        "integrating_sphere"
    };
    let pass = run_case(
        name,
        "integrating sphere, illuminance E [lx]",
        &case,
        &a.case,
    )?;
    anyhow::ensure!(
        pass,
        "Monte Carlo disagrees with the exact integrating-sphere solution"
    );
    Ok(())
}

/// `lumest validate plate`.
pub fn validate_plate(a: &PlateArgs) -> anyhow::Result<()> {
    anyhow::ensure!((0.0..=1.0).contains(&a.rho), "--rho must lie in [0, 1]");
    anyhow::ensure!(
        a.side > 0.0 && a.side.is_finite(),
        "--side must be positive"
    );
    anyhow::ensure!(a.points >= 3, "--points must be at least 3");
    let case = plate_case(a.side, a.rho, a.points);
    println!(
        "Square plate: side {} m, rho = {}, 100 cd at (0.3, 0.6, 0.8) a; {} points",
        a.side, a.rho, a.points
    );
    let pass = run_case("plate", "square plate, illuminance E [lx]", &case, &a.case)?;
    anyhow::ensure!(pass, "Monte Carlo disagrees with the plate reference");
    Ok(())
}

/// Arguments of `lumest validate box`.
#[derive(Args, Clone, Debug)]
pub struct BoxArgs {
    /// Reflectance of the walls (the floor gets half of it, the ceiling 0.9 of it).
    #[arg(long, default_value_t = 0.8)]
    pub rho: f64,
    /// Number of chains.
    #[arg(long, default_value_t = 1_000_000)]
    pub chains: u64,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Folder for the table (CSV) and plot (SVG).
    #[arg(long, default_value = "validation_report")]
    pub report: PathBuf,
}

/// Flux bookkeeping of a closed room, per face and in total [lm].
#[derive(Clone, Debug)]
pub struct FluxBalance {
    /// Flux absorbed by each surface [lm], mean and error over batches.
    pub absorbed: Vec<Welford>,
    /// Total absorbed [lm] per chain-batch mean.
    pub total: Welford,
    /// Chains that left the scene (a leak) or met a black back side.
    pub escaped: u64,
    /// Chains that met a black back side.
    pub back_side: u64,
    /// Emitted flux [lm].
    pub emitted: f64,
}

/// Trace `chains` chains in `batches` batches and account for every lumen:
/// at a collision of weight `Q` on a surface of albedo `a(wi)` the expected
/// absorbed flux is `Q (1 - a)`; a ray that leaves the scene or meets a
/// black back side takes its weight with it.
pub fn flux_balance(scene: &Scene, chains: u64, batches: u64, seed: u64) -> FluxBalance {
    let ns = scene.surfaces.len();
    let per = chains.div_ceil(batches);
    let params = ChainParams::default();
    let results: Vec<(Vec<f64>, u64, u64)> = (0..batches)
        .into_par_iter()
        .map(|b| {
            let mut abs = vec![0.0; ns];
            let (mut esc, mut back) = (0u64, 0u64);
            for c in 0..per {
                let mut rng = Philox4x32::new(seed, b * per + c);
                let u = [rng.next_2d(), rng.next_2d()];
                let (_, end) = trace_ex(scene, &mut rng, &params, u, |col| {
                    let m = &scene.surfaces[col.surface as usize].material;
                    let wi = crate::sampling::warp::Frame::from_normal(col.n).to_local(col.wi);
                    abs[col.surface as usize] += col.q * (1.0 - m.albedo(wi));
                });
                match end {
                    ChainEnd::Escaped => esc += 1,
                    ChainEnd::BackSide => back += 1,
                    _ => {}
                }
            }
            for v in &mut abs {
                *v /= per as f64;
            }
            (abs, esc, back)
        })
        .collect();
    let mut absorbed = vec![Welford::default(); ns];
    let mut total = Welford::default();
    let (mut escaped, mut back_side) = (0, 0);
    for (abs, e, bk) in results {
        for (w, v) in absorbed.iter_mut().zip(&abs) {
            w.push(*v);
        }
        total.push(abs.iter().sum());
        escaped += e;
        back_side += bk;
    }
    FluxBalance {
        absorbed,
        total,
        escaped,
        back_side,
        emitted: scene.total_power(),
    }
}

/// The furnished test room of `validate box`: a 5 x 4 x 3 m box with
/// inward normals, a solid desk (an outward box), a partition rectangle
/// reflecting on both sides, and two point lights.
pub fn box_room(rho: f64) -> Scene {
    let wall = Material::Lambertian { rho };
    let faces = [
        wall,
        wall,
        wall,
        wall,
        Material::Lambertian { rho: 0.5 * rho },
        Material::Lambertian { rho: 0.9 * rho },
    ];
    Scene::build(
        vec![
            SurfaceSpec::Box(
                "room".into(),
                AaBox {
                    lo: DVec3::ZERO,
                    hi: DVec3::new(5.0, 4.0, 3.0),
                },
                Sides::Back,
                faces,
            ),
            SurfaceSpec::Box(
                "desk".into(),
                AaBox {
                    lo: DVec3::new(1.0, 1.0, 0.0),
                    hi: DVec3::new(2.6, 1.8, 0.75),
                },
                Sides::Front,
                [Material::Lambertian { rho: 0.4 }; 6],
            ),
            SurfaceSpec::Rect(
                "partition".into(),
                Rect::new(DVec3::new(3.5, 0.0, 0.0), DVec3::Y * 2.0, DVec3::Z * 1.8).expect("rect"),
                Sides::Both,
                Material::Phong {
                    kd: 0.5,
                    ks: 0.3,
                    n: 20.0,
                },
            ),
        ],
        vec![
            Light::Point {
                p: DVec3::new(1.5, 2.0, 2.7),
                i: 300.0,
            },
            Light::Point {
                p: DVec3::new(4.0, 2.5, 2.7),
                i: 200.0,
            },
        ],
    )
    .expect("a valid programmatic scene")
}

/// `lumest validate box`: flux balance at growing numbers of chains (each
/// run independent), error against run time, and the per-surface table of
/// the largest run.
pub fn validate_box(a: &BoxArgs) -> anyhow::Result<()> {
    anyhow::ensure!((0.0..1.0).contains(&a.rho), "--rho must lie in [0, 1)");
    anyhow::ensure!(a.chains >= 64, "--chains must be at least 64");
    let scene = box_room(a.rho);
    eprintln!("lumest: scene: {}", scene.summary());
    let mut rows = Vec::new();
    let mut last = None;
    for k in (0..5).rev() {
        let chains = (a.chains >> k).max(64);
        let t0 = std::time::Instant::now();
        let fb = flux_balance(&scene, chains, 64, a.seed + k);
        let secs = t0.elapsed().as_secs_f64();
        let (m, se) = (fb.total.mean(), fb.total.std_error());
        let err = (m - fb.emitted).abs() / fb.emitted;
        let r = se / m;
        rows.push(super::validate::Checkpoint {
            time: secs,
            chains,
            batches: fb.total.count(),
            rms_err: err,
            max_err: err,
            rms_r: r,
            max_z: zcheck::z_score(m, se, fb.emitted).abs(),
            fom: crate::tally::figure_of_merit(r, secs),
        });
        last = Some(fb);
    }
    let fb = last.expect("five runs");
    println!("Closed box room: absorbed against emitted flux [lm], independent runs:");
    print_table(&rows);
    write_report(
        &a.report,
        "box_flux",
        &rows,
        "closed box room: flux balance against run time",
    )?;
    println!(
        "{:>16} {:>14} {:>12}",
        "surface", "absorbed_lm", "stderr_lm"
    );
    for (s, w) in scene.surfaces.iter().zip(&fb.absorbed) {
        println!("{:>16} {:>14.6} {:>12.3e}", s.name, w.mean(), w.std_error());
    }
    let z = zcheck::z_score(fb.total.mean(), fb.total.std_error(), fb.emitted);
    println!(
        "absorbed {:.6} +- {:.3e} lm, emitted {:.6} lm: z = {z:.2}; chains that escaped: {}, met a black side: {}",
        fb.total.mean(),
        fb.total.std_error(),
        fb.emitted,
        fb.escaped,
        fb.back_side
    );
    let bound = sidak_bound(0.01, rows.len(), Some(fb.total.count()));
    let zmax = zcheck::max_abs_z(rows.iter().map(|r| r.max_z));
    let pass = zcheck::within(zmax, bound) && fb.escaped == 0 && fb.back_side == 0;
    println!(
        "max |z| over the runs {zmax:.2} against the Sidak bound {bound:.2}: {}",
        if pass { "PASS" } else { "FAIL" }
    );
    anyhow::ensure!(pass, "flux balance fails: light leaks or is lost");
    Ok(())
}
