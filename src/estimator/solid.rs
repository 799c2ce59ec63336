//! Receiver types other than the plane: small solids whose illuminance is
//! the flux on their curved surface divided by its area.
//!
//! A receiver of any type reads `E = int_{S^2} L(wi) r(wi) dwi` \[lx\] with a
//! *response* `r` of the unit direction `wi` towards the source. A beam of
//! normal illuminance `E_n` from `wi` puts the flux `E_n A_proj(wi)` on a
//! small convex body (`A_proj`: the projected area of its lit part, which
//! nothing of the body shades), so `r = A_proj(wi) / A`, `A` the area of the
//! curved surface. For the types of the `receiver` column (the names are a
//! contract; CIE S 017:2020, ILV 17-21-055 and 17-21-066; EN 12464-1 and
//! EN 13201-2 for their use):
//!
//! - `planar` (the plane, `E`): `max(0, n . wi)` (not here: the local
//!   estimate's own kernel);
//! - `cylindrical` (`E_z`; axis `a`, the normal columns): a cylinder of
//!   radius `rho` and height `h` shows `2 rho h sin(theta)` to a beam at the
//!   angle `theta` from its axis, and its curved area is `2 pi rho h`:
//!   `r = sin(theta) / pi`;
//! - `semicylindrical` (`E_sz`; vertical axis, facing the horizontal `f`):
//!   the half shell at azimuths `phi` in `[-pi/2, pi/2]` about `f`, lit from
//!   the azimuth `alpha`, shows `rho h sin(theta) int max(0, cos(phi - alpha))
//!   dphi = rho h sin(theta) (1 + cos(alpha))` over the curved area
//!   `pi rho h`: `r = sin(theta) (1 + cos(alpha)) / pi = (sin(theta) + f . wi)
//!   / pi`; twice `E_z` for light from straight ahead, zero from behind;
//! - `hemispherical` (`E_hs`; pole `n`): the lit part of the dome projects
//!   to half a disc plus (or, from below the rim, minus) half an ellipse of
//!   semi-axes `rho` and `rho |cos(gamma)|`, `pi rho^2 (1 + cos(gamma)) / 2`,
//!   over the dome's area `2 pi rho^2`: `r = (1 + n . wi) / 4`, not zero below
//!   the rim (only straight from below);
//! - `spherical` (`E_o`, the scalar or mean spherical illuminance): `pi rho^2`
//!   over `4 pi rho^2`, `r = 1/4`, so `E_o = int L dw / 4`. This is the mean
//!   illuminance over a small sphere's surface of ILV 17-21-066 and of the
//!   lighting literature (Cuttle's scalar illuminance); the same entry's
//!   Note 2 divides by the diametral cross-section instead (`int L dw`, the
//!   "fluence rate" form, four times larger), which lumest does not use.
//!
//! In a uniform field of luminance `L` every type reads `pi L` (the
//! integrals of the responses over the sphere are all `pi`). For an
//! isotropic point source of intensity `I` at height `H` above the point, at
//! the angle `e` from the vertical (`E_perp = I cos^2(e) / H^2`) and the
//! azimuth `a` from the facing direction: `E_h = I cos^3(e) / H^2`,
//! `E_z = I cos^2(e) sin(e) / (pi H^2)`, `E_sz = I (1 + cos a) cos^2(e)
//! sin(e) / (pi H^2)`, `E_hs = I (1 + cos e) cos^2(e) / (4 H^2)` (pole up),
//! `E_o = I cos^2(e) / (4 H^2)`.
//!
//! Unlike a plane, a solid receiver sees the whole sphere of directions:
//! light from below its "normal" counts, so the local estimate scores into
//! it from every side ([`super::Receivers::score`]) and its own sampling
//! covers the sphere.

use crate::sampling::warp::{
    DirectionSample, cardioid_sphere_pdf, sample_cardioid_sphere, sample_uniform_sphere,
    uniform_sphere_pdf,
};
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// The receiver type names of the `receiver` column, in the order of the
/// docs (`planar` first, the default).
pub const RECEIVER_TYPES: [&str; 5] = [
    "planar",
    "cylindrical",
    "semicylindrical",
    "hemispherical",
    "spherical",
];

/// A solid receiver type (the plane is [`super::Response::Illuminance`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solid {
    /// Cylindrical illuminance `E_z` \[lx\] about the axis `n`.
    Cylindrical,
    /// Semi-cylindrical illuminance `E_sz` \[lx\]: vertical (world z) axis,
    /// facing the horizontal unit `n`.
    Semicylindrical,
    /// Hemispherical illuminance `E_hs` \[lx\], pole `n`.
    Hemispherical,
    /// Scalar (mean spherical) illuminance `E_o` \[lx\].
    Spherical,
}

impl Solid {
    /// The type named `name` of [`RECEIVER_TYPES`]: `Ok(None)` for
    /// `planar` (and an empty cell), an error message for an unknown name.
    pub fn parse(name: &str) -> Result<Option<Solid>, String> {
        match name {
            "" | "planar" => Ok(None),
            "cylindrical" => Ok(Some(Solid::Cylindrical)),
            "semicylindrical" => Ok(Some(Solid::Semicylindrical)),
            "hemispherical" => Ok(Some(Solid::Hemispherical)),
            "spherical" => Ok(Some(Solid::Spherical)),
            other => Err(format!(
                "unknown receiver type `{other}` (one of {})",
                RECEIVER_TYPES.join(", ")
            )),
        }
    }

    /// The type's name in [`RECEIVER_TYPES`].
    pub fn name(self) -> &'static str {
        match self {
            Solid::Cylindrical => "cylindrical",
            Solid::Semicylindrical => "semicylindrical",
            Solid::Hemispherical => "hemispherical",
            Solid::Spherical => "spherical",
        }
    }

    /// The response `r(wi)` \[1\] to light arriving from unit world direction
    /// `wi` (towards the source), `n` the receiver's unit normal (axis, facing
    /// direction or pole; module docs): `E = int L r dw`.
    #[inline]
    pub fn response(self, n: DVec3, wi: DVec3) -> f64 {
        match self {
            Solid::Cylindrical => {
                // sin = |n x wi|, free of the cancellation of sqrt(1 - c^2).
                n.cross(wi).length() * FRAC_1_PI
            }
            Solid::Semicylindrical => {
                let s = wi.x.hypot(wi.y);
                (s + n.dot(wi)).max(0.0) * FRAC_1_PI
            }
            Solid::Hemispherical => 0.25 * (1.0 + n.dot(wi)).max(0.0),
            Solid::Spherical => 0.25,
        }
    }

    /// Density [1/sr] of [`Self::sample`] at unit world `wi` (`n` the
    /// receiver's normal): uniform over the sphere for the cylinder and the
    /// sphere, `(1 + n . wi) / (4 pi)` for the hemisphere and the half
    /// cylinder.
    #[inline]
    pub fn pdf(self, n: DVec3, wi: DVec3) -> f64 {
        match self {
            Solid::Hemispherical | Solid::Semicylindrical => cardioid_sphere_pdf(n.dot(wi)),
            Solid::Cylindrical | Solid::Spherical => uniform_sphere_pdf(),
        }
    }

    /// A direction of the receiver's own sampling, in the local frame of
    /// its normal (z along `n`), with its density [1/sr]. The cylinder's
    /// `sin(theta)` has no elementary inverse: the uniform sphere keeps
    /// `r / pdf = 4 sin(theta)` within 4. The half cylinder's
    /// `sin(theta) + f . wi <= 1 + f . wi` makes the cardioid about its
    /// facing direction keep `r / pdf` within 4 too (the uniform sphere
    /// reached 8, and the backward estimate's variance three times the
    /// cylinder's in the integrating sphere test); the hemisphere's is 1.
    #[inline]
    pub fn sample(self, u: [f64; 2]) -> DirectionSample {
        match self {
            Solid::Hemispherical | Solid::Semicylindrical => sample_cardioid_sphere(u),
            Solid::Cylindrical | Solid::Spherical => sample_uniform_sphere(u),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::Frame;
    use std::f64::consts::PI;

    /// Midpoint product rule over the sphere of `f(w)`.
    fn sphere_integral(f: impl Fn(DVec3) -> f64) -> f64 {
        let (nt, np) = (800, 800);
        let mut s = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * PI / nt as f64;
            for k in 0..np {
                let p = (k as f64 + 0.5) * 2.0 * PI / np as f64;
                let w = DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                s += f(w) * t.sin();
            }
        }
        s * (PI / nt as f64) * (2.0 * PI / np as f64)
    }

    /// The flux fraction of a beam from `wi` on the curved surface of the
    /// body, by quadrature over that surface: `int max(0, m . wi) dA / A`
    /// with `m` the outward normal (a convex body does not shade itself).
    /// Written from the geometry, sharing nothing with `response`.
    fn projected_fraction(kind: Solid, n: DVec3, wi: DVec3) -> f64 {
        let frame = Frame::from_normal(n);
        let k = 20_000;
        let mut s = 0.0;
        match kind {
            // Curved surface of a cylinder: normals around the axis, each
            // azimuth an equal share of the area.
            Solid::Cylindrical => {
                for i in 0..k {
                    let p = (i as f64 + 0.5) * 2.0 * PI / k as f64;
                    let m = frame.to_world(DVec3::new(p.cos(), p.sin(), 0.0));
                    s += m.dot(wi).max(0.0);
                }
                s / k as f64
            }
            // Half shell about the facing direction n (horizontal), vertical axis.
            Solid::Semicylindrical => {
                let side = DVec3::Z.cross(n);
                for i in 0..k {
                    let p = -PI / 2.0 + (i as f64 + 0.5) * PI / k as f64;
                    let m = n * p.cos() + side * p.sin();
                    s += m.dot(wi).max(0.0);
                }
                s / k as f64
            }
            // Dome: area element sin(t) dt dp, t from the pole to the rim.
            Solid::Hemispherical | Solid::Spherical => {
                let t_max = if kind == Solid::Spherical {
                    PI
                } else {
                    PI / 2.0
                };
                let (nt, np) = (400, 400);
                let mut area = 0.0;
                for i in 0..nt {
                    let t = (i as f64 + 0.5) * t_max / nt as f64;
                    for j in 0..np {
                        let p = (j as f64 + 0.5) * 2.0 * PI / np as f64;
                        let m = frame.to_world(DVec3::new(
                            t.sin() * p.cos(),
                            t.sin() * p.sin(),
                            t.cos(),
                        ));
                        s += m.dot(wi).max(0.0) * t.sin();
                        area += t.sin();
                    }
                }
                s / area
            }
        }
    }

    fn unit(v: DVec3) -> DVec3 {
        v.normalize()
    }

    #[test]
    fn responses_are_the_projected_area_over_the_curved_area() {
        let dirs = [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            unit(DVec3::new(0.3, -0.5, 0.8)),
            unit(DVec3::new(-0.7, 0.2, -0.4)),
            unit(DVec3::new(0.1, 0.9, -0.05)),
            unit(DVec3::new(-1.0, -0.1, 0.3)),
        ];
        let normals = [
            (Solid::Cylindrical, unit(DVec3::new(0.2, 0.1, 1.0))),
            (Solid::Semicylindrical, unit(DVec3::new(1.0, 0.5, 0.0))),
            (Solid::Hemispherical, unit(DVec3::new(0.0, -0.3, 1.0))),
            (Solid::Spherical, DVec3::Z),
        ];
        for (kind, n) in normals {
            for wi in dirs {
                let want = projected_fraction(kind, n, wi);
                let got = kind.response(n, wi);
                assert!((got - want).abs() < 2e-5, "{kind:?} {wi}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn every_type_reads_pi_l_in_a_uniform_field_and_pdfs_integrate_to_one() {
        let n = unit(DVec3::new(0.6, -0.8, 0.0));
        for kind in [
            Solid::Cylindrical,
            Solid::Semicylindrical,
            Solid::Hemispherical,
            Solid::Spherical,
        ] {
            let e = sphere_integral(|w| kind.response(n, w));
            assert!((e / PI - 1.0).abs() < 1e-5, "{kind:?}: {e}");
            let p = sphere_integral(|w| kind.pdf(n, w));
            assert!((p - 1.0).abs() < 1e-5, "{kind:?}: {p}");
            // The sampler's record matches its pdf, in the frame of n.
            let frame = Frame::from_normal(n);
            for u in [[0.1, 0.2], [0.5, 0.9], [0.97, 0.4]] {
                let s = kind.sample(u);
                let w = frame.to_world(s.w);
                assert!((s.pdf - kind.pdf(n, w)).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn point_source_closed_forms() {
        // I at height H, angle e from the vertical, azimuth a from the facing.
        let (i, h) = (1000.0, 2.5);
        for (e, a) in [(0.3_f64, 0.0_f64), (0.9, 1.2), (1.3, 2.9), (0.0, 0.5)] {
            let wi = DVec3::new(e.sin() * a.cos(), e.sin() * a.sin(), e.cos());
            let e_perp = i * e.cos().powi(2) / (h * h);
            let e_of = |kind: Solid, n: DVec3| e_perp * kind.response(n, wi);
            let (c, s) = (e.cos(), e.sin());
            let cases = [
                (
                    e_of(Solid::Cylindrical, DVec3::Z),
                    i * c * c * s / (PI * h * h),
                ),
                (
                    e_of(Solid::Semicylindrical, DVec3::X),
                    i * (1.0 + a.cos()) * c * c * s / (PI * h * h),
                ),
                (
                    e_of(Solid::Hemispherical, DVec3::Z),
                    i * (1.0 + c) * c * c / (4.0 * h * h),
                ),
                (e_of(Solid::Spherical, DVec3::Z), i * c * c / (4.0 * h * h)),
            ];
            for (got, want) in cases {
                assert!(
                    (got - want).abs() <= 1e-12 * want.max(1e-300),
                    "{got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn names_are_the_contract() {
        for name in RECEIVER_TYPES {
            match Solid::parse(name).unwrap() {
                None => assert_eq!(name, "planar"),
                Some(s) => assert_eq!(s.name(), name),
            }
        }
        assert_eq!(Solid::parse(""), Ok(None));
        assert!(
            Solid::parse("cylinder")
                .unwrap_err()
                .contains("cylindrical")
        );
    }
}
