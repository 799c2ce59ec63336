//! Discomfort glare: the Unified Glare Rating (CIE 117-1995) of an observer
//! at an eye position looking along a line of sight,
//!
//! `UGR = 8 log10( (0.25 / L_b) sum_i L_i^2 omega_i / p_i^2 )`
//!
//! - `L_i` [cd/m^2]: the luminance of luminaire `i`'s luminous parts seen
//!   from the eye, `I_i(w) / A_p` with `I_i(w)` its intensity towards the
//!   eye and `A_p` the luminous area projected on the plane normal to `w`;
//! - `omega_i = A_p / d^2` \[sr\]: their solid angle from the eye at distance
//!   `d` (CIE 117's definition);
//! - `p_i`: Guth's position index ([`position_index`]);
//! - `L_b = E_ind / pi` [cd/m^2]: the background luminance, with `E_ind`
//!   \[lx\] the indirect illuminance at the eye on the plane normal to the
//!   line of sight (light reflected at least once; the local estimate gives
//!   it directly, with its standard error).
//!
//! Each term `L^2 omega / p^2 = I^2 / (A_p d^2 p^2)` is exact (the
//! photometric table interpolated, the geometry closed-form); only `E_ind`
//! is a Monte Carlo estimate, and its error carries to the rating
//! ([`Ugr::from_parts`]).
//!
//! Which luminaires count: those in the field of CIE 117's table of
//! position indices ([`in_position_field`]): in front of the observer
//! (`R > 0` along the line of sight), at or above it (`H >= 0` along the
//! observer's up direction), within `T/R <= 3` and `H/R <= 1.9` and not
//! where the brows hide them; of which the eye sees some part: a
//! luminaire partly hidden (behind a screen, a beam) counts
//! with the solid angle of the part it sees ([`visible_part`]), its
//! luminance unchanged.
//!
//! Luminous areas: a goniometric luminaire's from its file's luminous
//! shape ([`crate::io::photometry::OpeningShape`]: every shape of LM-63-2002's
//! table, EULUMDAT's rectangle and disc), each projected exactly along the
//! direction of the eye ([`crate::light::luminous_parts`] gives the closed forms): a
//! rectangle's or an ellipse's bottom `A |cos gamma|` when the eye lies
//! below the luminaire's plane, plus its luminous sides (`h w |w_x| + h l
//! |w_y|` for a rectangle, `h D sin gamma` for a disc of diameter `D`);
//! an ellipsoid's outline (`pi r^2` for a sphere); a horizontal
//! cylinder's end and mantle; a vertical ellipse's `pi a b |cos|`; an
//! area source's own surface (its average luminance `Phi / (pi A)` per
//! emitting side); a sphere light's
//! disc `pi r^2`. Point and spot lights have no luminous area: a glare
//! calculation refuses them. Lights at infinity (sky, sun, environment)
//! are not luminaires here; their reflected light is part of `E_ind`.

pub mod scene_observers;
pub mod tabular;
pub mod visible_part;

use crate::io::photometry::OpeningShape;
use crate::light::Light;
use crate::scene::Scene;
use glam::DVec3;
use std::f64::consts::{LN_10, PI};

/// Guth's position index from the angles of the source seen by the eye:
/// `tau` \[deg\], the angle from the vertical of the plane through the line
/// of sight and the source (0: straight above the line of sight, 90: level
/// with it, to the side), and `sigma` \[deg\], the angle between the line of
/// sight and the direction of the source.
///
/// `ln p = (35.2 - 0.31889 tau - 1.22 e^(-2 tau / 9)) 1e-3 sigma
///        + (21 + 0.26667 tau - 0.002963 tau^2) 1e-5 sigma^2`
///
/// the closed form fitted to Guth's tabulated position index (Luckiesh &
/// Guth 1949; the fit as published by Levin, J. IES 4 (1975) 99-105, and
/// used by Radiance's `glarendx`, whose `posindex` has the same constants).
/// It reproduces the table's `T/R = 0` column (CIE 117-1995, IES Handbook)
/// within 4 % (tested). CIE 117-1995 (4.5) prescribes interpolating its
/// Table 4.1 instead, which leaves out luminaires beyond `T/R = 3` and the
/// positions hidden by brows (left out here too, [`in_position_field`]);
/// Levin gives the fit's largest departure from
/// Guth's plot as about 12 % (0.8 on the rating for one dominant
/// luminaire). That table is not bundled: ratings here are the fit's.
pub fn guth_index(tau_deg: f64, sigma_deg: f64) -> f64 {
    let (t, s) = (tau_deg, sigma_deg);
    let a = (35.2 - 0.31889 * t - 1.22 * (-2.0 * t / 9.0).exp()) * 1e-3;
    let b = (21.0 + 0.26667 * t - 0.002963 * t * t) * 1e-5;
    (a * s + b * s * s).exp()
}

/// Guth's position index of a source at `r` \[m\] ahead along the line of
/// sight, `t` \[m\] to the side and `h` \[m\] above it (CIE 117's `R`, `T`,
/// `H`; only ratios matter): [`guth_index`] of `tau = atan2(|t|, h)` and
/// `sigma = atan2(sqrt(t^2 + h^2), r)`. 1 on the line of sight.
pub fn position_index(r: f64, t: f64, h: f64) -> f64 {
    let off = t.hypot(h);
    if off == 0.0 {
        return 1.0;
    }
    let tau = t.abs().atan2(h).to_degrees();
    let sigma = off.atan2(r).to_degrees();
    guth_index(tau, sigma)
}

/// Whether a source at `r` \[m\] ahead along the line of sight, `t` \[m\] to
/// the side and `h` \[m\] above it lies in the field of CIE 117-1995's Table
/// 4.1 of position indices, the field a rating counts: ahead (`R > 0`) and
/// at or above the line of sight (`H >= 0`), where the table's nearest
/// node (steps of 0.1 in `T/R` and `H/R`) has an index: `T/R` up to 3 and
/// `H/R` up to 1.9, less the table's dashes where the brows hide a source
/// (`H/R = 1.8` and `1.9` for `T/R <= 0.3`, `H/R = 1.9` for `T/R = 0.4 ..
/// 0.8`). The nearest node decides, so that a position a rounding away
/// from a node (an eye a millimetre off the standard room's wall) is
/// treated as the node. CIE 117 leaves luminaires outside the field out
/// of the rating.
pub fn in_position_field(r: f64, t: f64, h: f64) -> bool {
    if !(r > 0.0 && h >= 0.0) {
        return false;
    }
    let (tr, hr) = (t.abs() / r, h / r);
    let hidden = (tr < 0.35 && hr >= 1.75) || (tr < 0.85 && hr >= 1.85);
    tr < 3.05 && hr < 1.95 && !hidden
}

/// An observer: the eye \[m\] and the unit line of sight, with the frame
/// the position index is measured in (`up`: the world `+z` made normal to
/// the line of sight; `side` completes it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observer {
    /// Eye position \[m\].
    pub eye: DVec3,
    /// Unit line of sight.
    pub view: DVec3,
    /// Unit up direction, normal to `view`.
    pub up: DVec3,
    /// Unit direction to the observer's right (`view x up`).
    pub side: DVec3,
}

impl Observer {
    /// The observer at `eye` looking along `view` (any length > 0); `None`
    /// when the line of sight is vertical (within 1e-6) or not finite: the
    /// position index needs an up direction.
    pub fn new(eye: DVec3, view: DVec3) -> Option<Self> {
        let v = view.try_normalize()?;
        if !eye.is_finite() || v.z.abs() > 1.0 - 1e-6 {
            return None;
        }
        let up = (DVec3::Z - v * v.z).normalize();
        Some(Self {
            eye,
            view: v,
            up,
            side: v.cross(up),
        })
    }
}

/// The luminous parts of one luminaire, as glare needs them.
#[derive(Clone, Debug, PartialEq)]
pub enum LuminousArea {
    /// A goniometric luminaire: its file's luminous shape (LM-63-2002's
    /// shapes; EULUMDAT's rectangle or disc) and half its extents \[m\]
    /// along the local `x` (C0, the length), `y` (C90, the width) and `z`
    /// (the height) axes: for a rectangle or an ellipse facing down, `z`
    /// is half the height of its luminous sides (0: none).
    Gonio {
        /// The shape.
        shape: OpeningShape,
        /// Half the extents \[m\] along local `x`, `y`, `z`.
        half: DVec3,
    },
    /// A flat Lambertian source of `area` [m^2] facing `normal`, of average
    /// luminance `l` [cd/m^2] on its emitting side(s).
    Flat {
        /// Area of one side [m^2].
        area: f64,
        /// Unit front normal.
        normal: DVec3,
        /// Whether the back emits too.
        two_sided: bool,
        /// Average luminance [cd/m^2].
        l: f64,
    },
    /// A Lambertian sphere of radius `r` \[m\] and luminance `l` [cd/m^2].
    Sphere {
        /// Radius \[m\].
        r: f64,
        /// Luminance [cd/m^2].
        l: f64,
    },
}

impl LuminousArea {
    /// The luminous parts a photometric file gives (its shape and its
    /// dimensions \[m\]); an error when it gives none, or a shape with a
    /// zero or non-finite dimension.
    pub fn of_file(o: &crate::io::photometry::Opening) -> Result<Self, GlareError> {
        // The luminous shape the near-field emission takes, too.
        if let Some(s) = crate::light::LuminousShape::of(o) {
            return Ok(LuminousArea::Gonio {
                shape: s.shape,
                half: s.half,
            });
        }
        let (w, l, h) = (o.width.abs(), o.length.abs(), o.height.abs());
        Err(GlareError::NoArea(if o.shape == OpeningShape::Point {
            "its photometric file gives no luminous area (width and length 0): \
             UGR needs the luminance of the luminous parts"
                .to_string()
        } else {
            format!(
                "its photometric file's luminous shape ({}, width {w} m, length {l} m, \
                 height {h} m) has no area: UGR needs the luminance of the luminous parts",
                o.shape.name(w, l, h)
            )
        }))
    }

    /// Projected luminous area [m^2] seen along unit world direction `w`
    /// (from the luminaire towards the eye), for a luminaire with local
    /// axes `frame` (goniometric only).
    pub fn projected(&self, w: DVec3, frame: &crate::light::LuminaireFrame) -> f64 {
        match self {
            LuminousArea::Gonio { shape, half } => {
                crate::light::luminous_parts::parts(*shape, *half, frame.to_local(w), false)
                    .iter()
                    .map(|p| p.0)
                    .sum()
            }
            LuminousArea::Flat {
                area,
                normal,
                two_sided,
                ..
            } => {
                let c = w.dot(*normal);
                if c > 0.0 || *two_sided {
                    area * c.abs()
                } else {
                    0.0
                }
            }
            LuminousArea::Sphere { r, .. } => PI * r * r,
        }
    }
}

/// Why a light cannot take part in a glare calculation.
#[derive(Clone, Debug, PartialEq)]
pub enum GlareError {
    /// A point or spot light, or a photometric file without luminous
    /// dimensions: no luminance without an area.
    NoArea(String),
}

impl std::fmt::Display for GlareError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GlareError::NoArea(what) => write!(f, "{what}"),
        }
    }
}

/// The luminous area of light `light`; `Ok(None)` for lights that are not
/// luminaires (distant, environment: lights at infinity).
pub fn luminous_area(light: &Light) -> Result<Option<LuminousArea>, GlareError> {
    match light {
        Light::Gonio { dist, .. } => LuminousArea::of_file(&dist.file_opening()).map(Some),
        Light::Area(a) => {
            let sides = if a.two_sided { 2.0 } else { 1.0 };
            Ok(Some(LuminousArea::Flat {
                area: a.area(),
                normal: a.normal(),
                two_sided: a.two_sided,
                l: a.power() / (sides * PI * a.area()),
            }))
        }
        Light::Sphere { r, i, .. } => Ok(Some(LuminousArea::Sphere {
            r: *r,
            l: i / (PI * r * r),
        })),
        Light::Point { .. } | Light::Spot(_) => Err(GlareError::NoArea(
            "a point or spot light has no luminous area: UGR needs the luminance of the \
             luminous parts (use an IES/LDT luminaire with luminous dimensions, or an area source)"
                .to_string(),
        )),
        Light::Distant(_) | Light::Environment(_) => Ok(None),
    }
}

/// One luminaire's share of an observer's glare.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlareTerm {
    /// Index of the light in the scene.
    pub light: usize,
    /// Luminance of its luminous parts towards the eye [cd/m^2].
    pub l: f64,
    /// Solid angle of its luminous parts that the eye sees \[sr\]: `seen`
    /// times that of the whole parts.
    pub omega: f64,
    /// The fraction of the luminous parts' projected area that the eye
    /// sees ([`visible_part::visible_fraction`]; 1 when nothing is in the
    /// way).
    pub seen: f64,
    /// Guth's position index.
    pub p: f64,
    /// Distance from the eye to its centre \[m\].
    pub d: f64,
}

impl GlareTerm {
    /// `L^2 omega / p^2` [(cd/m^2)^2 sr].
    pub fn value(&self) -> f64 {
        self.l * self.l * self.omega / (self.p * self.p)
    }
}

/// A luminaire's centre \[m\], intensity \[cd\] towards unit world direction
/// `w`, and local frame; `None` for lights at infinity.
fn centre_and_intensity(
    light: &Light,
    w: DVec3,
) -> Option<(DVec3, f64, crate::light::LuminaireFrame)> {
    use crate::light::LuminaireFrame;
    match light {
        Light::Gonio { p, frame, dist, .. } => Some((*p, dist.intensity_world(frame, w), *frame)),
        Light::Area(a) => Some((a.center(), 0.0, LuminaireFrame::DEFAULT)),
        Light::Sphere { c, i, .. } => Some((*c, *i, LuminaireFrame::DEFAULT)),
        Light::Point { p, i } => Some((*p, *i, LuminaireFrame::DEFAULT)),
        Light::Spot(s) => Some((s.p, 0.0, LuminaireFrame::DEFAULT)),
        Light::Distant(_) | Light::Environment(_) => None,
    }
}

/// The glare term of light `k` (luminous parts `area`) for `obs`; `None`
/// when it does not count: outside the position-index field
/// ([`in_position_field`]: behind the observer, below the line of sight,
/// beyond `T/R = 3` or `H/R = 1.9`, or hidden by the brows), wholly hidden
/// from the eye, dark towards it, or seen edge-on.
pub fn glare_term(
    scene: &Scene,
    k: usize,
    area: &LuminousArea,
    obs: &Observer,
) -> Option<GlareTerm> {
    let light = &scene.lights[k];
    let (c, _, _) = centre_and_intensity(light, DVec3::Z)?;
    let v = c - obs.eye;
    let (r, t, h) = (v.dot(obs.view), v.dot(obs.side), v.dot(obs.up));
    if !in_position_field(r, t, h) {
        return None;
    }
    let d = v.length();
    // Unit direction from the luminaire to the eye.
    let w = -v / d;
    let (_, i, frame) = centre_and_intensity(light, w)?;
    let a_p = area.projected(w, &frame);
    if a_p <= 0.0 {
        return None;
    }
    let seen = visible_part::visible_fraction(scene, light, area, (c, &frame), obs.eye, w);
    if seen <= 0.0 {
        return None;
    }
    let l = match area {
        LuminousArea::Gonio { .. } => i / a_p,
        LuminousArea::Flat { l, .. } | LuminousArea::Sphere { l, .. } => *l,
    };
    if l <= 0.0 {
        return None;
    }
    Some(GlareTerm {
        light: k,
        l,
        omega: seen * a_p / (d * d),
        p: position_index(r, t, h),
        d,
        seen,
    })
}

/// CIE 117's formula: `8 log10(0.25 sum / L_b)` with `L_b = e / pi`, from
/// the glare sum `sum` [(cd/m^2)^2 sr] and the background illuminance `e`
/// \[lx\] (at the eye, or the walls' average in the tabular method).
pub fn ugr_formula(sum: f64, e: f64) -> f64 {
    8.0 * (0.25 * PI * sum / e).log10()
}

/// The rating and its uncertainty at one observer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ugr {
    /// `sum L^2 omega / p^2` over the luminaires that count [(cd/m^2)^2 sr] (exact).
    pub sum: f64,
    /// Background luminance `E_ind / pi` [cd/m^2].
    pub lb: f64,
    /// Its standard error [cd/m^2].
    pub lb_std_error: f64,
    /// The rating; `None` when undefined (no luminaire counts, or no
    /// indirect light reaches the eye).
    pub value: Option<f64>,
    /// Standard error of the rating (delta method: `8 / ln 10 * se_E / E`).
    pub std_error: Option<f64>,
    /// 95 % interval: the Student-t interval of `E_ind` mapped through the
    /// (decreasing) rating; the high end is `None` (unbounded) when the
    /// interval of `E_ind` reaches 0.
    pub ci95: Option<(f64, Option<f64>)>,
}

impl Ugr {
    /// The rating of a glare sum `sum` over a background from the
    /// indirect illuminance `e_ind` \[lx\] at the eye, its standard error
    /// `se` \[lx\] and the half-width factor `t` of its 95 % interval
    /// (`t_{0.975, B-1}` for `B` batches).
    pub fn from_parts(sum: f64, e_ind: f64, se: f64, t: f64) -> Self {
        let lb = e_ind / PI;
        let lb_std_error = se / PI;
        let rating = |e: f64| ugr_formula(sum, e);
        if !(sum > 0.0 && e_ind > 0.0 && sum.is_finite() && e_ind.is_finite() && se.is_finite()) {
            return Self {
                sum,
                lb,
                lb_std_error,
                value: None,
                std_error: None,
                ci95: None,
            };
        }
        let (lo_e, hi_e) = (e_ind - t * se, e_ind + t * se);
        Self {
            sum,
            lb,
            lb_std_error,
            value: Some(rating(e_ind)),
            std_error: Some(8.0 / LN_10 * se / e_ind),
            ci95: Some((rating(hi_e), (lo_e > 0.0).then(|| rating(lo_e)))),
        }
    }
}

/// CIE 117's range of solid angles for which the formula holds \[sr\]:
/// smaller sources (below 3e-4 sr) need CIE 147's correction, larger ones
/// (above 0.1 sr) are large-area glare.
pub const OMEGA_RANGE: (f64, f64) = (3e-4, 0.1);

#[cfg(test)]
mod tests {
    use super::*;

    /// The field of CIE 117's Table 4.1: its extent and the dashes where
    /// the brows hide a source, node by node and between nodes (the
    /// nearest node decides).
    #[test]
    fn position_field_is_the_tables() {
        for (t, h) in [
            (0.0, 0.0),
            (3.0, 1.9),
            (3.04, 1.94),
            (0.3, 1.7),
            (0.4, 1.8),
            (0.9, 1.9),
            (2.0, 1.0),
        ] {
            assert!(
                in_position_field(1.0, t, h),
                "T/R {t}, H/R {h} has an index"
            );
            assert!(
                in_position_field(2.0, -2.0 * t, 2.0 * h),
                "only ratios and |T| matter"
            );
        }
        for (t, h) in [
            (0.0, 1.8),
            (0.3, 1.8),
            (0.3, 1.9),
            (0.8, 1.9),
            (0.5, 1.86),
            (3.06, 0.0),
            (1.0, 1.96),
            (0.0, -0.01),
        ] {
            assert!(!in_position_field(1.0, t, h), "T/R {t}, H/R {h} has none");
        }
        assert!(!in_position_field(-1.0, 0.0, 0.0) && !in_position_field(0.0, 0.0, 0.0));
    }

    /// Guth's table (CIE 117-1995 / IES Handbook), column `T/R = 0`, rows
    /// `H/R = 0, 0.1, ..., 1.0` and 1.5: the closed form is within 4 %
    /// (its fit error); and at an exact evaluation it matches the formula
    /// computed by hand to 1e-12.
    #[test]
    fn position_index_against_guth_table() {
        let table = [
            (0.0, 1.00),
            (0.1, 1.26),
            (0.2, 1.53),
            (0.3, 1.90),
            (0.4, 2.35),
            (0.5, 2.86),
            (0.6, 3.50),
            (0.7, 4.20),
            (0.8, 5.00),
            (0.9, 6.00),
            (1.0, 7.00),
            (1.5, 13.15),
        ];
        let mut worst: f64 = 0.0;
        for (hr, p) in table {
            let q = position_index(1.0, 0.0, hr);
            worst = worst.max((q / p - 1.0).abs());
        }
        assert!(worst < 0.04, "worst relative deviation {worst}");
        // A 10 % error in the index would show: the mid-range entries fit to 1 %.
        for (hr, p) in [(0.5, 2.86), (0.6, 3.50), (0.9, 6.00), (1.0, 7.00)] {
            let q = position_index(1.0, 0.0, hr);
            assert!((q / p - 1.0).abs() < 0.015, "H/R {hr}: {q} vs {p}");
        }
        // By hand: tau = 0, sigma = 45 deg: ln p = 0.03398 * 45 + 21e-5 * 2025.
        let ln_p: f64 = (35.2 - 1.22) * 1e-3 * 45.0 + 21e-5 * 2025.0;
        assert!((position_index(2.0, 0.0, 2.0) - ln_p.exp()).abs() < 1e-12);
        // Level with the eye, to the side: tau = 90.
        let a = (35.2 - 0.31889 * 90.0 - 1.22 * (-20.0f64).exp()) * 1e-3;
        let b = (21.0 + 0.26667 * 90.0 - 0.002963 * 8100.0) * 1e-5;
        let s = 45.0;
        assert!((position_index(1.0, -1.0, 0.0) - (a * s + b * s * s).exp()).abs() < 1e-12);
        assert_eq!(position_index(3.0, 0.0, 0.0), 1.0);
    }

    /// The rating's error and interval: delta method and the mapped t
    /// interval, and undefined cases.
    #[test]
    fn rating_from_parts() {
        let u = Ugr::from_parts(1e6, 100.0, 2.0, 2.0);
        let want = 8.0 * (0.25 * PI * 1e6 / 100.0).log10();
        assert!((u.value.unwrap() - want).abs() < 1e-12);
        assert!((u.std_error.unwrap() - 8.0 / LN_10 * 0.02).abs() < 1e-12);
        let (lo, hi) = u.ci95.unwrap();
        assert!((lo - 8.0 * (0.25 * PI * 1e6 / 104.0).log10()).abs() < 1e-12);
        assert!((hi.unwrap() - 8.0 * (0.25 * PI * 1e6 / 96.0).log10()).abs() < 1e-12);
        // An interval of E reaching 0: unbounded above.
        assert_eq!(Ugr::from_parts(1e6, 1.0, 1.0, 2.0).ci95.unwrap().1, None);
        assert_eq!(Ugr::from_parts(0.0, 1.0, 0.1, 2.0).value, None);
        assert_eq!(Ugr::from_parts(1.0, 0.0, 0.0, 2.0).value, None);
        assert_eq!(Ugr::from_parts(1.0, f64::NAN, 0.0, 2.0).value, None);
    }

    #[test]
    fn observer_frame() {
        let o = Observer::new(DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0)).unwrap();
        assert_eq!(o.up, DVec3::Z);
        assert!((o.side - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-15);
        assert!(Observer::new(DVec3::ZERO, DVec3::Z).is_none());
        assert!(Observer::new(DVec3::ZERO, DVec3::ZERO).is_none());
    }
}
