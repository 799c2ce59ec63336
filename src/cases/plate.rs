//! A point source over a square Lambertian plate, against 2-D quadrature
//! ([`crate::reference::closed_form::PlateCase`]); `lumest validate plate`.

use super::case::{Case, CaseArgs, run_case};
use crate::estimator::Receiver;
use crate::geometry::shapes::Rect;
use crate::light::Light;
use crate::material::Material;
use crate::reference::closed_form::{PlateCase, point_illuminance};
use crate::sampling::Philox4x32;
use crate::scene::{Scene, Sides, SurfaceSpec};
use clap::Args;
use glam::DVec3;

/// Arguments of `lumest validate plate`.
#[derive(Args, Clone, Debug)]
pub struct PlateArgs {
    /// Side of the square plate (m).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub side: f64,
    /// Reflectance of the plate.
    #[arg(long, default_value_t = 0.8, allow_negative_numbers = true)]
    pub rho: f64,
    /// Number of points.
    #[arg(long, default_value_t = 40, allow_negative_numbers = true)]
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
    let (receivers, exact): (Vec<Receiver>, Vec<f64>) = lit.into_iter().unzip();
    // The point in the plate's shadow faces its black back over most of
    // its hemisphere: flagged `enclosed` by design (its E is exactly 0).
    let expected_flags = (0..exact.len())
        .filter(|&j| exact[j] == 0.0)
        .map(|j| (j, "enclosed"))
        .collect();
    Case {
        scene,
        receivers,
        exact,
        expected_flags,
    }
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
