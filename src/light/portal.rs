//! Portals (`[[portal]]`): rectangles that are the only way the light of
//! distant lights, environment maps and skies enters the part of the scene
//! that matters (a room's windows). With portals, the chains of those
//! lights start on the portals instead of on a plane across the whole
//! scene: a point uniform over the portals' total area, a direction drawn
//! from the light as without portals, and the flux the light sends through
//! the portal there, `L cos / (pdf_dir pdf_area)` with `cos` the angle to
//! the portal's normal. A direction that would leave through the portal,
//! or whose light is blocked before it reaches the portal (an overhang, the
//! building's own walls), carries nothing: the chain checks the segment
//! from the portal towards the light ([`crate::chain`]). Light that enters
//! the scene elsewhere than through a portal is left out, so the portals
//! must cover every opening; the estimate is then the one without portals,
//! only with fewer chains wasted outside.

use glam::DVec3;

/// One portal: the parallelogram `corner + a edge1 + b edge2`, `a, b` in
/// `[0, 1]`, whose normal `edge1 x edge2` points into the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    /// A corner \[m\].
    pub corner: DVec3,
    /// First edge \[m\].
    pub e1: DVec3,
    /// Second edge \[m\].
    pub e2: DVec3,
    /// Unit normal `edge1 x edge2`, into the scene.
    pub n: DVec3,
    /// Area [m^2].
    pub area: f64,
}

impl Portal {
    /// The portal of a corner and two edges; `None` when degenerate.
    pub fn new(corner: DVec3, e1: DVec3, e2: DVec3) -> Option<Self> {
        let c = e1.cross(e2);
        let area = c.length();
        (area > 0.0 && area.is_finite()).then(|| Self {
            corner,
            e1,
            e2,
            n: c / area,
            area,
        })
    }
}

/// The scene's portals, picked in proportion to area.
#[derive(Clone, Debug, PartialEq)]
pub struct Portals {
    list: Vec<Portal>,
    /// Cumulative areas [m^2].
    cum: Vec<f64>,
}

impl Portals {
    /// The set of `list` (non-empty).
    pub fn new(list: Vec<Portal>) -> Self {
        let mut acc = 0.0;
        let cum = list
            .iter()
            .map(|p| {
                acc += p.area;
                acc
            })
            .collect();
        Self { list, cum }
    }

    /// The portals.
    pub fn list(&self) -> &[Portal] {
        &self.list
    }

    /// Total area [m^2].
    pub fn area(&self) -> f64 {
        self.cum.last().copied().unwrap_or(0.0)
    }

    /// A point uniform over the portals' total area from `u`, with the
    /// normal of its portal; the density is `1 / area()` [1/m^2].
    pub fn sample(&self, u: [f64; 2]) -> (DVec3, DVec3) {
        let total = self.area();
        let x = u[0] * total;
        let k = self
            .cum
            .partition_point(|&c| c <= x)
            .min(self.list.len() - 1);
        let lo = if k > 0 { self.cum[k - 1] } else { 0.0 };
        let p = &self.list[k];
        // The rest of u[0] within the portal's share, rescaled to [0, 1).
        let a = ((x - lo) / p.area).clamp(0.0, 1.0);
        (p.corner + p.e1 * a + p.e2 * u[1], p.n)
    }

    /// Distance along the ray from `x` in unit direction `wi` to portal
    /// `p`, and the cosine `|wi . n|`, if the ray crosses it.
    fn crossing(p: &Portal, x: DVec3, wi: DVec3) -> Option<(f64, f64)> {
        let dn = wi.dot(p.n);
        if dn == 0.0 {
            return None;
        }
        let t = (p.corner - x).dot(p.n) / dn;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        // Coordinates of the crossing in the edges' (dual) basis.
        let q = x + wi * t - p.corner;
        let (g11, g12, g22) = (p.e1.dot(p.e1), p.e1.dot(p.e2), p.e2.dot(p.e2));
        let det = g11 * g22 - g12 * g12;
        let (b1, b2) = (q.dot(p.e1), q.dot(p.e2));
        let a = (b1 * g22 - b2 * g12) / det;
        let b = (b2 * g11 - b1 * g12) / det;
        ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some((t, dn.abs()))
    }

    /// A direction from `x` through a point drawn uniformly over the
    /// portals' area from `u`, with its density [1/sr] ([`Self::pdf`]);
    /// `None` when `x` lies in the point's portal plane.
    pub fn sample_direction(&self, x: DVec3, u: [f64; 2]) -> Option<(DVec3, f64)> {
        let (y, _) = self.sample(u);
        let v = y - x;
        let t2 = v.length_squared();
        if t2 <= 0.0 || t2.is_nan() {
            return None;
        }
        let wi = v / t2.sqrt();
        let pdf = self.pdf(x, wi);
        (pdf > 0.0 && pdf.is_finite()).then_some((wi, pdf))
    }

    /// Density [1/sr] of [`Self::sample_direction`] from `x` towards unit
    /// `wi`: `sum_k t_k^2 / (A |cos_k|)` over the portals the ray crosses
    /// (at distance `t_k`, cosine `cos_k`), `A` the total area.
    pub fn pdf(&self, x: DVec3, wi: DVec3) -> f64 {
        let inv_a = 1.0 / self.area();
        self.list
            .iter()
            .filter_map(|p| Self::crossing(p, x, wi))
            .map(|(t, c)| t * t * inv_a / c)
            .sum()
    }

    /// `sum_k area_k int f(wi) max(0, -wi . n_k) dwi`: the flux \[lm\] a
    /// distant source of luminance `f` [cd/m^2] (by direction towards it)
    /// sends into the scene through the portals, unobstructed, given as a
    /// sum over `cells` of (direction towards the source, luminance, solid
    /// angle \[sr\]).
    pub fn flux(&self, cells: impl Iterator<Item = (DVec3, f64, f64)> + Clone) -> f64 {
        self.list
            .iter()
            .map(|p| {
                p.area
                    * cells
                        .clone()
                        .map(|(wi, l, omega)| l * (-wi.dot(p.n)).max(0.0) * omega)
                        .sum::<f64>()
            })
            .sum()
    }

    /// The emitted ray of a light whose direction of travel `d` was drawn
    /// with density `pdf_dir` [1/sr] (1 for a collimated light) carrying
    /// luminance `le` (or illuminance, collimated) across the portals: the
    /// start point from `u_pos` and the flux \[lm\] the ray carries (0 when
    /// `d` leaves through the portal).
    pub fn emission(&self, d: DVec3, le: f64, pdf_dir: f64, u_pos: [f64; 2]) -> (DVec3, f64, f64) {
        let (o, n) = self.sample(u_pos);
        let cos = d.dot(n);
        let pdf_pos = 1.0 / self.area();
        let phi = if cos > 0.0 {
            le * cos / (pdf_dir * pdf_pos)
        } else {
            0.0
        };
        (o, pdf_pos, phi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_are_uniform_over_the_total_area() {
        let a = Portal::new(DVec3::ZERO, DVec3::X, DVec3::Y * 2.0).unwrap();
        let b = Portal::new(DVec3::new(5.0, 0.0, 0.0), DVec3::Y, DVec3::Z).unwrap();
        let ps = Portals::new(vec![a, b]);
        assert_eq!(ps.area(), 3.0);
        let (mut na, mut n) = (0, 0);
        for i in 0..300 {
            for j in 0..10 {
                let (p, nrm) = ps.sample([(i as f64 + 0.5) / 300.0, (j as f64 + 0.5) / 10.0]);
                if p.x < 1.5 {
                    na += 1;
                    assert_eq!(nrm, DVec3::Z);
                    assert!(p.y >= 0.0 && p.y <= 2.0 && p.x <= 1.0);
                } else {
                    assert_eq!(nrm, DVec3::X);
                }
                n += 1;
            }
        }
        // Two thirds of the area, two thirds of the points.
        assert_eq!(na * 3, n * 2);
        assert!(Portal::new(DVec3::ZERO, DVec3::X, DVec3::X).is_none());
    }

    /// The direction density integrates to the portals' total solid angle
    /// share: drawn directions follow it (mean of 1/pdf over the draws is
    /// the solid angle the portals subtend, against a fine quadrature).
    #[test]
    fn direction_density_is_consistent() {
        let ps = Portals::new(vec![
            Portal::new(DVec3::new(-1.0, -0.5, 2.0), DVec3::X * 2.0, DVec3::Y).unwrap(),
            Portal::new(DVec3::new(3.0, -1.0, 0.0), DVec3::Y * 2.0, DVec3::Z * 1.5).unwrap(),
        ]);
        let x = DVec3::new(0.2, 0.1, 0.3);
        let mut rng = crate::sampling::Philox4x32::new(4, 0);
        let (mut s, n) = (0.0, 200_000);
        for _ in 0..n {
            let (wi, pdf) = ps.sample_direction(x, rng.next_2d()).unwrap();
            assert!((ps.pdf(x, wi) - pdf).abs() < 1e-12 * pdf);
            s += 1.0 / pdf;
        }
        let omega_mc = s / n as f64;
        // Quadrature of the solid angle: directions on a fine sphere grid
        // that cross a portal.
        let m = 1000;
        let mut omega = 0.0;
        for i in 0..m {
            let ct = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
            let st = (1.0 - ct * ct).sqrt();
            for j in 0..2 * m {
                let ph = std::f64::consts::PI * (j as f64 + 0.5) / m as f64;
                let w = DVec3::new(st * ph.cos(), st * ph.sin(), ct);
                if ps.pdf(x, w) > 0.0 {
                    omega += 1.0;
                }
            }
        }
        omega *= 4.0 * std::f64::consts::PI / (2 * m * m) as f64;
        assert!(
            (omega_mc / omega - 1.0).abs() < 5e-3,
            "{omega_mc} vs {omega}"
        );
    }

    #[test]
    fn flux_through_a_portal() {
        let p = Portals::new(vec![Portal::new(DVec3::ZERO, DVec3::X, DVec3::Y).unwrap()]);
        // A collimated beam of 1000 lx travelling down at 60 degrees from
        // the normal... the portal's normal is +z: light entering travels
        // along +z, from a source below (wi towards the source = -z side).
        let wi = DVec3::new(0.0, (60f64).to_radians().sin(), -(60f64).to_radians().cos());
        let f = p.flux([(wi, 1000.0, 1.0)].into_iter());
        assert!((f - 500.0).abs() < 1e-9, "{f}");
        let (_, pdf, phi) = p.emission(-wi, 1000.0, 1.0, [0.3, 0.7]);
        assert_eq!(pdf, 1.0);
        assert!((phi - 500.0).abs() < 1e-9);
        // Leaving through the portal: nothing.
        assert_eq!(p.emission(wi, 1000.0, 1.0, [0.3, 0.7]).2, 0.0);
    }
}
