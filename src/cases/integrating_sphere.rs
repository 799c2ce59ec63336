//! The integrating sphere with an off-centre point source, against the
//! closed-form uniform indirect illuminance; `lumest validate integrating-sphere`.

use super::case::{Case, CaseArgs, run_case};
use crate::estimator::Receiver;
use crate::geometry::sh::{ShCoeff, ShSurface};
use crate::geometry::shapes::Sphere;
use crate::io::format_number;
use crate::light::Light;
use crate::material::Material;
use crate::reference::closed_form::{integrating_sphere_indirect, point_illuminance};
use crate::scene::{Scene, Sides, SurfaceSpec};
use clap::Args;
use glam::DVec3;
use std::f64::consts::PI;

/// Arguments of `lumest validate integrating-sphere`.
#[derive(Args, Clone, Debug)]
pub struct SphereArgs {
    /// Wall reflectance, in [0, 1).
    #[arg(long, default_value_t = 0.9, allow_negative_numbers = true)]
    pub rho: f64,
    /// Radius (m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub radius: f64,
    /// Source position relative to the centre, in units of the radius: `x,y,z`.
    #[arg(long, default_value = "0.3,-0.2,0.45", allow_hyphen_values = true)]
    pub source: String,
    /// Number of points on the wall.
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
    pub points: usize,
    /// Give the sphere as a degree-0 spherical-harmonic object instead.
    #[arg(long)]
    pub sh: bool,
    #[command(flatten)]
    pub case: CaseArgs,
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
        expected_flags: Vec::new(),
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
