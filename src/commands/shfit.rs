//! `lumest sh-fit`: fit a star-shaped triangle mesh by a spherical-harmonic
//! expansion (least squares), report the fit error and storage, and with
//! `--compare T` run the same scene with the mesh and with its fit.
//!
//! Samples: rays from the centre in `--samples` nearly uniform directions
//! (a Fibonacci spiral) meet the mesh once each (star-shaped about the
//! centre), so the fit weights every direction alike, whatever the mesh's
//! vertex density. The error is then measured on an independent spiral
//! four times denser: radial distance between the mesh and the expansion.

use crate::cases::integrating_sphere::spiral;
use crate::estimator::local::run;
use crate::estimator::{Receiver, Receivers};
use crate::geometry::Plane;
use crate::geometry::mesh::Mesh;
use crate::geometry::sh::{MAX_DEGREE, ShSurface, fit, write_coefficients};
use crate::light::Light;
use crate::material::Material;
use crate::run::RunConfig;
use crate::scene::{Scene, Sides, SurfaceSpec};
use crate::tally::zcheck;
use anyhow::Context;
use clap::Args;
use glam::{DMat3, DVec3};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `lumest sh-fit`.
#[derive(Args, Clone, Debug)]
pub struct ShFitArgs {
    /// Star-shaped mesh (OBJ).
    pub mesh: PathBuf,
    /// Degree L of the expansion ((L + 1)^2 coefficients).
    #[arg(long, allow_negative_numbers = true)]
    pub degree: usize,
    /// Output CSV of coefficients `k,m,a,b` (m).
    #[arg(long)]
    pub out: PathBuf,
    /// Centre of the expansion `x,y,z` (m) (default: the mesh's volume centroid).
    #[arg(long, allow_hyphen_values = true)]
    pub center: Option<String>,
    /// Number of sample directions (default: max(4000, 20 (L + 1)^2)).
    #[arg(long, allow_negative_numbers = true)]
    pub samples: Option<usize>,
    /// Also run a scene (floor, object, point light, 48 points) with the mesh
    /// and with the fit for this many seconds each, and compare.
    #[arg(long, allow_negative_numbers = true)]
    pub compare: Option<f64>,
    /// Worker threads for `--compare` (0: all cores).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub threads: usize,
}

/// Most sample directions `--samples` may ask for.
pub const MAX_SAMPLES: usize = 2_000_000;

/// Most bytes the least-squares fit may take (see [`sh_fit`]): 4 GB.
const MAX_FIT_BYTES: f64 = 4e9;

/// Volume centroid of a closed mesh (divergence theorem); the bounding-box
/// centre when the enclosed volume is (nearly) zero.
pub fn volume_centroid(mesh: &Mesh) -> DVec3 {
    let (lo, hi) = mesh.bounds();
    let o = 0.5 * (lo + hi);
    let (mut v, mut c) = (0.0, DVec3::ZERO);
    for t in 0..mesh.triangle_count() as u32 {
        let [a, b, d] = mesh.corners(t).map(|p| p - o);
        let det = a.dot(b.cross(d)) / 6.0;
        v += det;
        c += (a + b + d) / 4.0 * det;
    }
    if v.abs() <= 1e-12 * (hi - lo).length().powi(3) {
        o
    } else {
        o + c / v
    }
}

/// Distance from `center` to the mesh along each unit direction: its one
/// hit. Errors if a ray misses (the mesh is not closed around the centre)
/// or meets the mesh again beyond its first hit (it is not star-shaped
/// about the centre: `r(theta, phi)` would keep the nearer surface and drop
/// the rest, a ring around a ball or the far arm of a U, and the fit error
/// measured on the same first hits would not show it).
fn radii(mesh: &Mesh, center: DVec3, dirs: &[DVec3]) -> anyhow::Result<Vec<f64>> {
    dirs.iter()
        .map(|&d| {
            let (t, _, tri) = mesh
                .first_hit(center, d, 0.0, f64::INFINITY, None, None)
                .ok_or_else(|| {
                    anyhow::anyhow!(
                        "the ray from the centre {center} along {d} misses the mesh: \
                         it is not closed around the centre (give --center)"
                    )
                })?;
            // Beyond the first hit by more than rounding (a ray through a
            // shared edge meets both triangles at the same distance).
            if let Some((t2, _, _)) =
                mesh.first_hit(center, d, t * (1.0 + 1e-9), f64::INFINITY, Some(tri), None)
            {
                anyhow::bail!(
                    "the ray from the centre {center} along {d} meets the mesh at {} m and again \
                     at {} m: the mesh is not star-shaped about the centre, and r(theta, phi) \
                     would drop its farther parts (give a --center from which every ray meets \
                     it once, or fit the parts separately)",
                    crate::io::format_number(t),
                    crate::io::format_number(t2)
                );
            }
            Ok(t)
        })
        .collect()
}

fn parse_vec(s: &str) -> anyhow::Result<DVec3> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--center `{s}`"))?;
    anyhow::ensure!(
        v.len() == 3 && v.iter().all(|x| x.is_finite()),
        "--center: three finite numbers x,y,z"
    );
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// Run `lumest sh-fit`.
pub fn sh_fit(a: &ShFitArgs) -> anyhow::Result<()> {
    // Sizes first: the samples, the check spiral and the least-squares
    // matrix grow with (L + 1)^2.
    anyhow::ensure!(
        a.degree <= MAX_DEGREE,
        "--degree {}: at most {MAX_DEGREE}",
        a.degree
    );
    if let Some(n) = a.samples {
        anyhow::ensure!(
            n <= MAX_SAMPLES,
            "--samples {n}: at most {MAX_SAMPLES} (the check uses four times as many rays)"
        );
    }
    if let Some(t) = a.compare {
        // Checked before the fit writes its coefficients.
        anyhow::ensure!(
            t > 0.0 && t.is_finite(),
            "--compare: a positive number of seconds, got {}",
            crate::io::format_number(t)
        );
    }
    super::outputs::check_outputs(&[a.mesh.as_path()], &[("--out", a.out.as_path())])?;
    let t0 = Instant::now();
    let mesh = Mesh::load_obj(&a.mesh).map_err(|e| anyhow::anyhow!("{e}"))?;
    let load_s = t0.elapsed().as_secs_f64();
    let center = match &a.center {
        Some(c) => parse_vec(c)?,
        None => volume_centroid(&mesh),
    };
    let n_coef = (a.degree + 1).pow(2);
    let samples = a.samples.unwrap_or((20 * n_coef).max(4000));
    anyhow::ensure!(
        samples >= n_coef,
        "--samples must be at least (L + 1)^2 = {n_coef}"
    );
    // The least-squares fit holds the dense design matrix, its copy and
    // the SVD's factor of the same size: three samples x coefficients
    // arrays (--degree 100 took 50 GB and aborted).
    let bytes = 3.0 * 8.0 * samples as f64 * n_coef as f64;
    anyhow::ensure!(
        bytes <= MAX_FIT_BYTES,
        "--degree {} with {samples} samples needs about {:.1} GB for the least-squares fit \
         (at most {:.0} GB): take a lower degree or fewer --samples (at least (L + 1)^2 = {n_coef})",
        a.degree,
        bytes / 1e9,
        MAX_FIT_BYTES / 1e9
    );
    let dirs = spiral(samples);
    let r = radii(&mesh, center, &dirs)?;
    let pts: Vec<DVec3> = dirs.iter().zip(&r).map(|(d, r)| center + *d * *r).collect();
    let t1 = Instant::now();
    let f = fit(&pts, center, a.degree).map_err(|e| anyhow::anyhow!("{e}"))?;
    let fit_s = t1.elapsed().as_secs_f64();
    let sh = ShSurface::new(&f.coeffs, DVec3::ZERO, DMat3::IDENTITY, 1.0).map_err(|e| {
        anyhow::anyhow!("the fitted expansion is not a valid star-shaped surface: {e}")
    })?;
    // Independent check on a denser spiral.
    let check = spiral(4 * samples);
    let rc = radii(&mesh, center, &check)?;
    let (mut s2, mut emax) = (0.0f64, 0.0f64);
    for (d, r) in check.iter().zip(&rc) {
        let e = sh.radius(*d) - r;
        s2 += e * e;
        emax = emax.max(e.abs());
    }
    let rms = (s2 / check.len() as f64).sqrt();
    write_coefficients(&a.out, &f.coeffs)
        .with_context(|| format!("writing {}", a.out.display()))?;
    let sh_placed = ShSurface::new(&f.coeffs, center, DMat3::IDENTITY, 1.0)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    println!(
        "mesh {}: {} triangles, {} vertices, loaded with its BVH in {:.3} s",
        a.mesh.display(),
        mesh.triangle_count(),
        mesh.vertices().len(),
        load_s
    );
    println!(
        "centre {center}; degree {} ({} coefficients) fitted to {} ray samples in {:.3} s",
        a.degree, n_coef, samples, fit_s
    );
    println!(
        "fit residual at the samples: RMS {:.3e} m, max {:.3e} m; against the mesh on {} other directions: \
         RMS {:.3e} m, max {:.3e} m (mean radius {:.4} m: RMS {:.3e}, max {:.3e} relative)",
        f.rms_residual,
        f.max_residual,
        check.len(),
        rms,
        emax,
        f.mean_radius,
        rms / f.mean_radius,
        emax / f.mean_radius
    );
    println!(
        "storage: mesh + BVH {} bytes, SH {} bytes ({:.1}x smaller); OBJ file {} bytes, CSV {} bytes",
        mesh.storage_bytes(),
        sh_placed.storage_bytes(),
        mesh.storage_bytes() as f64 / sh_placed.storage_bytes() as f64,
        std::fs::metadata(&a.mesh).map_or(0, |m| m.len()),
        std::fs::metadata(&a.out).map_or(0, |m| m.len())
    );
    eprintln!("lumest: wrote {}", a.out.display());
    if let Some(t) = a.compare {
        compare(mesh, sh_placed, center, f.mean_radius, t, a.threads);
    }
    Ok(())
}

/// The object (mesh or SH) standing on a floor under a point light, 48
/// points: 32 on the floor around it, 16 around its upper half facing out.
fn comparison_scene(
    obj: SurfaceSpec,
    center: DVec3,
    r: f64,
    shape: &ShSurface,
) -> (Scene, Vec<Receiver>) {
    let floor_z = center.z - 1.6 * r;
    let scene = Scene::build(
        vec![
            SurfaceSpec::Plane(
                "floor".into(),
                Plane::new(DVec3::new(0.0, 0.0, floor_z), DVec3::Z),
                Material::Lambertian { rho: 0.5 },
            ),
            obj,
        ],
        vec![Light::Point {
            p: center + DVec3::new(1.5 * r, 0.7 * r, 3.0 * r),
            i: 100.0,
        }],
    )
    .expect("a valid programmatic scene");
    let mut rec = Vec::new();
    for k in 0..32 {
        let a = std::f64::consts::TAU * k as f64 / 32.0;
        let rho = r * (1.6 + 0.05 * k as f64);
        let p = DVec3::new(center.x + rho * a.cos(), center.y + rho * a.sin(), floor_z);
        rec.push(Receiver::illuminance(p, DVec3::Z));
    }
    // Points a quarter of the radius off the object's surface, facing out:
    // off both the mesh and its fit, whatever the fit's error.
    for d in spiral(32).into_iter().filter(|d| d.z > 0.0).take(16) {
        let rr = shape.radius(d);
        rec.push(Receiver::illuminance(center + d * rr * 1.25, d));
    }
    (scene, rec)
}

fn compare(mesh: Mesh, sh: ShSurface, center: DVec3, r: f64, t: f64, threads: usize) {
    let m = Material::Lambertian { rho: 0.7 };
    let cfg = RunConfig::timed(7, threads, t);
    println!(
        "{:>6} {:>8} {:>12} {:>11} {:>11} {:>10} {:>11}",
        "object", "time_s", "chains", "chains/s", "scores/s", "rms_R", "FOM"
    );
    let mut res = Vec::new();
    for (name, spec) in [
        (
            "mesh",
            SurfaceSpec::Mesh("object".into(), mesh.clone(), Sides::Front, m),
        ),
        (
            "SH",
            SurfaceSpec::Sh("object".into(), sh.clone(), Sides::Front, m),
        ),
    ] {
        let (scene, rec) = comparison_scene(spec, center, r, &sh);
        let receivers = Receivers::from_receivers(&scene, &rec).expect("valid receivers");
        let out = run(&scene, &receivers, &cfg, &mut |_| true);
        let rms = out.tallies.rms_rel_error(&out.direct);
        println!(
            "{:>6} {:>8.2} {:>12} {:>11.4e} {:>11.4e} {:>10.3e} {:>11.4e}",
            name,
            out.wall,
            out.chains,
            out.chains as f64 / out.wall,
            out.scores as f64 / out.wall,
            rms,
            crate::tally::figure_of_merit(rms, out.wall)
        );
        res.push(out);
    }
    let (a, b) = (&res[0], &res[1]);
    let mut zmax: f64 = 0.0;
    let mut dmax: f64 = 0.0;
    for j in 0..a.direct.len() {
        let (ea, eb) = (
            a.direct[j] + a.tallies.estimated[j].mean(),
            b.direct[j] + b.tallies.estimated[j].mean(),
        );
        let se = (a.tallies.estimated[j].std_error().powi(2)
            + b.tallies.estimated[j].std_error().powi(2))
        .sqrt();
        // Relative to the larger of the two (both 0: no difference; the
        // mesh's 0 against the fit's light used to print 2.8e299).
        let scale = ea.abs().max(eb.abs());
        if scale > 0.0 {
            dmax = zcheck::max_abs(dmax, (ea - eb) / scale);
        }
        zmax = zcheck::max_abs(zmax, zcheck::z_score(ea, se, eb));
    }
    println!(
        "cost per chain, SH / mesh: {:.2}; largest relative difference of E over the 48 points {:.3e} \
         (max |z| of the difference {:.2}: the fit's shape error, not noise, when large)",
        (a.chains as f64 / a.wall) / (b.chains as f64 / b.wall),
        dmax,
        zmax
    );
}
