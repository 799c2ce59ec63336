//! The luminous parts of a goniometric luminaire's LM-63 shape seen along
//! a direction: each part's area projected on the plane normal to the
//! direction, and a map from the unit square onto the part, uniform in
//! that projected area, with the outward normal at each point. The glare
//! model ([`crate::glare::LuminousArea::projected`],
//! [`crate::glare::visible_part`]) and the near-field emission of a
//! luminaire (`opening = true`, [`crate::light::LuminousShape`]) both take
//! their areas and points from here, so the two cannot disagree.
//!
//! Coordinates are the luminaire's local ones \[m\] (`x` along C0, `y` along
//! C90, `z` up, the nadir `-z`), centred on its photometric centre; `half`
//! holds half the shape's extents along them.
//!
//! Projected areas along a unit local direction `d` (closed forms; each
//! checked against ray casting through the solid in the tests):
//! - rectangle `2a x 2b` (`a` along `x`) with sides `2c` tall: the bottom
//!   `4ab max(-d_z, 0)` (it faces the nadir only), the sides `2c (2b |d_x|
//!   + 2a |d_y|)`; `closed` adds the top, `4ab max(d_z, 0)`;
//! - ellipse of semi-axes `a, b` with sides `2c` tall (a vertical elliptical
//!   cylinder): the bottom `pi a b max(-d_z, 0)`, the sides `2c 2 sqrt(a^2
//!   d_y^2 + b^2 d_x^2)` (the ellipse's width across `d`); `closed` adds
//!   the top, `pi a b max(d_z, 0)`;
//! - ellipsoid of semi-axes `a, b, c`: `pi sqrt(b^2 c^2 d_x^2 + a^2 c^2 d_y^2
//!   + a^2 b^2 d_z^2)` (`pi r^2` for a sphere);
//! - horizontal cylinder along `x`, `2a` long, cross-section semi-axes `b,
//!   c`: the end facing the eye `pi b c |d_x|` plus the mantle `2a 2 sqrt(b^2
//!   d_z^2 + c^2 d_y^2)`; along `y` likewise with the axes exchanged;
//! - vertical ellipse facing `x` (semi-axes `b, c`): `pi b c |d_x|` (both
//!   faces luminous); facing `y` likewise.
//!
//! Glare leaves the top out (`closed = false`: UGR's eyes look up at
//! luminaires, and LM-63 names luminous sides, not a luminous top). Emission
//! takes the closed solid (`closed = true`): a luminaire with luminous sides
//! whose file also sends light upwards emits it through its top, as
//! Radiance's `ies2rad` builds such a source, and a flat opening emits its
//! upward light through its upper face, so that every direction with light
//! has a part to leave from.

use crate::io::photometry::OpeningShape;
use glam::DVec3;
use std::f64::consts::PI;

/// One luminous part, as a map from the unit square to its points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Part {
    /// Nothing (a part turned away from the eye).
    None,
    /// A rectangle: `c + e1 (2 u0 - 1) + e2 (2 u1 - 1)`, its unit normal
    /// `n` the one facing the eye.
    Rectangle {
        c: DVec3,
        e1: DVec3,
        e2: DVec3,
        n: DVec3,
    },
    /// A flat ellipse of semi-axis vectors `e1`, `e2`, uniform by area, its
    /// unit normal `n` the one facing the eye.
    Ellipse {
        c: DVec3,
        e1: DVec3,
        e2: DVec3,
        n: DVec3,
    },
    /// The half of an elliptical cylinder's mantle that faces the eye:
    /// cross-section `c + e1 cos phi + e2 sin phi`, `axis` half its length;
    /// `phi0` the facing direction in the unit-circle parameter (points
    /// uniform in the projected width: `phi = phi0 + asin(2 u0 - 1)`).
    Mantle {
        c: DVec3,
        e1: DVec3,
        e2: DVec3,
        axis: DVec3,
        phi0: f64,
    },
    /// The half of an ellipsoid of semi-axes `half` that faces the eye:
    /// the unit sphere's cap facing `dir` (the direction mapped to the unit
    /// sphere), uniform in its projected disc, scaled by `half`.
    Cap { half: DVec3, dir: DVec3 },
}

impl Part {
    /// The point of the part at `u` (local coordinates \[m\]).
    pub fn point(&self, u: [f64; 2]) -> DVec3 {
        self.point_normal(u).0
    }

    /// The point of the part at `u` (local coordinates \[m\]) and the unit
    /// normal of the surface there, on the side facing the eye (outward on
    /// a solid).
    pub fn point_normal(&self, u: [f64; 2]) -> (DVec3, DVec3) {
        match *self {
            Part::None => (DVec3::ZERO, DVec3::Z),
            Part::Rectangle { c, e1, e2, n } => {
                (c + e1 * (2.0 * u[0] - 1.0) + e2 * (2.0 * u[1] - 1.0), n)
            }
            Part::Ellipse { c, e1, e2, n } => {
                let r = u[0].sqrt();
                let (s, co) = crate::sampling::warp::sin_cos_turns(u[1]);
                (c + e1 * (r * co) + e2 * (r * s), n)
            }
            Part::Mantle {
                c,
                e1,
                e2,
                axis,
                phi0,
            } => {
                let phi = phi0 + (2.0 * u[0] - 1.0).asin();
                let (s, co) = phi.sin_cos();
                // The cross-section's outward normal: the gradient of
                // (p.e1 / |e1|^2)^2 + (p.e2 / |e2|^2)^2 at the point.
                let n = (e1 * (co / e1.length_squared()) + e2 * (s / e2.length_squared()))
                    .normalize_or(e1.normalize_or_zero());
                (c + e1 * co + e2 * s + axis * (2.0 * u[1] - 1.0), n)
            }
            Part::Cap { half, dir } => {
                let f = crate::sampling::warp::Frame::from_normal(dir);
                let rho = u[0].sqrt();
                let (s, co) = crate::sampling::warp::sin_cos_turns(u[1]);
                let z = (1.0 - rho * rho).max(0.0).sqrt();
                let unit = f.to_world(DVec3::new(rho * co, rho * s, z));
                // The ellipsoid's normal: the unit sphere's, scaled by 1 / half.
                (unit * half, (unit / half).normalize_or(dir))
            }
        }
    }
}

/// The luminous parts of `shape` with half-extents `half` \[m\] seen along
/// unit local direction `d` (from the luminaire towards the eye): up to
/// three, each with its projected area [m^2] (0 with [`Part::None`]).
/// With `closed`, a rectangle or an ellipse (flat, or with luminous sides)
/// also has its top, facing up (module docs).
pub fn parts(shape: OpeningShape, half: DVec3, d: DVec3, closed: bool) -> [(f64, Part); 3] {
    let none = (0.0, Part::None);
    let mut out = [none; 3];
    let (a, b, c) = (half.x, half.y, half.z);
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    match shape {
        OpeningShape::Point => {}
        OpeningShape::Rectangle | OpeningShape::Ellipse => {
            let round = shape == OpeningShape::Ellipse;
            // The bottom, `c` below the centre, faces the nadir; the top,
            // `c` above it, the zenith (closed solids only).
            let (cap_c, facing, n) = if d.z < 0.0 || !closed {
                (-c * z, (-d.z).max(0.0), -z)
            } else {
                (c * z, d.z, z)
            };
            out[0] = if round {
                (
                    PI * a * b * facing,
                    Part::Ellipse {
                        c: cap_c,
                        e1: a * x,
                        e2: b * y,
                        n,
                    },
                )
            } else {
                (
                    4.0 * a * b * facing,
                    Part::Rectangle {
                        c: cap_c,
                        e1: a * x,
                        e2: b * y,
                        n,
                    },
                )
            };
            if c > 0.0 {
                if round {
                    let width = if a == b {
                        2.0 * a * d.x.hypot(d.y)
                    } else {
                        2.0 * (a * d.y).hypot(b * d.x)
                    };
                    out[1] = (
                        2.0 * c * width,
                        Part::Mantle {
                            c: DVec3::ZERO,
                            e1: a * x,
                            e2: b * y,
                            axis: c * z,
                            phi0: (d.y / b).atan2(d.x / a),
                        },
                    );
                } else {
                    // The side normal to unit `e` (half-extent `h`, the
                    // direction's component `de` along it) that faces the
                    // eye, spanned by `o` (half-extent `ho`) and z.
                    let side = |e: DVec3, h: f64, de: f64, o: DVec3, ho: f64| {
                        (
                            2.0 * c * 2.0 * ho * de.abs(),
                            Part::Rectangle {
                                c: h * de.signum() * e,
                                e1: ho * o,
                                e2: c * z,
                                n: de.signum() * e,
                            },
                        )
                    };
                    out[1] = side(x, a, d.x, y, b);
                    out[2] = side(y, b, d.y, x, a);
                }
            }
        }
        OpeningShape::Ellipsoid => {
            let area = PI * (b * c * d.x).hypot(a * c * d.y).hypot(a * b * d.z);
            let dir = (d / half).normalize_or(DVec3::Z);
            out[0] = (area, Part::Cap { half, dir });
        }
        OpeningShape::CylinderC0 => out = cylinder(d, a, b, c, [x, y, z]),
        OpeningShape::CylinderC90 => {
            // Axis along y: the same with (x, y) exchanged.
            out = cylinder(DVec3::new(d.y, d.x, d.z), b, a, c, [y, x, z]);
        }
        OpeningShape::VerticalEllipseC0 => out[0] = vertical_ellipse(d.x, x, (b, y), (c, z)),
        OpeningShape::VerticalEllipseC90 => out[0] = vertical_ellipse(d.y, y, (a, x), (c, z)),
    }
    out
}

/// A vertical ellipse through the centre, luminous on both faces, of
/// semi-axes `s1` along unit `e1` and `s2` along unit `e2`, seen with
/// `facing` the direction's component along its unit normal `normal`.
fn vertical_ellipse(
    facing: f64,
    normal: DVec3,
    (s1, e1): (f64, DVec3),
    (s2, e2): (f64, DVec3),
) -> (f64, Part) {
    (
        PI * s1 * s2 * facing.abs(),
        Part::Ellipse {
            c: DVec3::ZERO,
            e1: s1 * e1,
            e2: s2 * e2,
            n: normal * facing.signum(),
        },
    )
}

/// A horizontal cylinder along axis `ex`, half length `a`, cross-section
/// semi-axes `b` (along `ey`) and `c` (along `ez`), seen along `d` given in
/// the `(ex, ey, ez)` components: its end facing the eye and its mantle.
fn cylinder(d: DVec3, a: f64, b: f64, c: f64, [ex, ey, ez]: [DVec3; 3]) -> [(f64, Part); 3] {
    let end = (
        PI * b * c * d.x.abs(),
        Part::Ellipse {
            c: a * d.x.signum() * ex,
            e1: b * ey,
            e2: c * ez,
            n: d.x.signum() * ex,
        },
    );
    let mantle = (
        2.0 * a * 2.0 * (b * d.z).hypot(c * d.y),
        Part::Mantle {
            c: DVec3::ZERO,
            e1: b * ey,
            e2: c * ez,
            axis: a * ex,
            phi0: (d.z / c).atan2(d.y / b),
        },
    );
    [end, mantle, (0.0, Part::None)]
}

/// Where the ray `o + t v` (local coordinates \[m\], `v` a unit direction)
/// enters the closed luminous solid `shape` of half extents `half` from
/// outside: the least `t > 0` at which it meets the solid, or where it
/// crosses a flat shape (a rectangle or an ellipse without sides at
/// `z = 0`, a vertical ellipse) within its outline; `None` where it misses,
/// and where it starts inside the solid (the shape emits outwards only).
/// The views of a luminaire emitting from its shape see it there
/// ([`crate::light::Light::shape_luminance`]).
pub fn entry(shape: OpeningShape, half: DVec3, o: DVec3, v: DVec3) -> Option<f64> {
    use OpeningShape as S;
    let (x, y, z, h) = (DVec3::X, DVec3::Y, DVec3::Z, half);
    // A flat outline in the plane through the centre normal to `n`.
    let flat = |n: DVec3, inside: &dyn Fn(DVec3) -> bool| {
        let q = v.dot(n);
        if q.abs() < 1e-300 {
            return None;
        }
        let t = -o.dot(n) / q;
        (t > 0.0 && inside(o + v * t)).then_some(t)
    };
    let (t0, _) = match shape {
        S::Point => return None,
        S::Rectangle | S::Ellipse if h.z == 0.0 => {
            return if shape == S::Rectangle {
                flat(z, &|p| p.x.abs() <= h.x && p.y.abs() <= h.y)
            } else {
                flat(z, &|p| (p.x / h.x).powi(2) + (p.y / h.y).powi(2) <= 1.0)
            };
        }
        S::Rectangle => meet(
            meet(slab(o, v, x, h.x), slab(o, v, y, h.y)),
            slab(o, v, z, h.z),
        ),
        S::Ellipse => meet(ecyl(o, v, (x, h.x), (y, h.y)), slab(o, v, z, h.z)),
        S::Ellipsoid => {
            let (o1, v1) = (o / h, v / h);
            let (qa, qb, qc) = (v1.dot(v1), 2.0 * o1.dot(v1), o1.dot(o1) - 1.0);
            let disc = qb * qb - 4.0 * qa * qc;
            (disc >= 0.0).then(|| {
                let s = disc.sqrt();
                ((-qb - s) / (2.0 * qa), (-qb + s) / (2.0 * qa))
            })
        }
        S::CylinderC0 => meet(slab(o, v, x, h.x), ecyl(o, v, (y, h.y), (z, h.z))),
        S::CylinderC90 => meet(slab(o, v, y, h.y), ecyl(o, v, (x, h.x), (z, h.z))),
        S::VerticalEllipseC0 => {
            return flat(x, &|p| (p.y / h.y).powi(2) + (p.z / h.z).powi(2) <= 1.0);
        }
        S::VerticalEllipseC90 => {
            return flat(y, &|p| (p.x / h.x).powi(2) + (p.z / h.z).powi(2) <= 1.0);
        }
    }?;
    (t0 > 0.0).then_some(t0)
}

/// The parameter interval where the line `o + t v` lies in the slab
/// `|p . e| <= h` (`None` when it misses).
fn slab(o: DVec3, v: DVec3, e: DVec3, h: f64) -> Option<(f64, f64)> {
    let (p, q) = (o.dot(e), v.dot(e));
    if q.abs() < 1e-300 {
        return (p.abs() <= h).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let (t0, t1) = ((-h - p) / q, (h - p) / q);
    Some((t0.min(t1), t0.max(t1)))
}

/// The interval inside the elliptical cylinder `(p.e1/a)^2 + (p.e2/b)^2 <= 1`.
fn ecyl(o: DVec3, v: DVec3, (e1, a): (DVec3, f64), (e2, b): (DVec3, f64)) -> Option<(f64, f64)> {
    let (o1, o2, v1, v2) = (o.dot(e1) / a, o.dot(e2) / b, v.dot(e1) / a, v.dot(e2) / b);
    let qa = v1 * v1 + v2 * v2;
    let (qb, qc) = (2.0 * (o1 * v1 + o2 * v2), o1 * o1 + o2 * o2 - 1.0);
    if qa < 1e-300 {
        return (qc <= 0.0).then_some((f64::NEG_INFINITY, f64::INFINITY));
    }
    let disc = qb * qb - 4.0 * qa * qc;
    (disc >= 0.0).then(|| {
        let s = disc.sqrt();
        ((-qb - s) / (2.0 * qa), (-qb + s) / (2.0 * qa))
    })
}

fn meet(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> Option<(f64, f64)> {
    let (a, b) = (a?, b?);
    let (t0, t1) = (a.0.max(b.0), a.1.min(b.1));
    (t0 <= t1).then_some((t0, t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shapes under test: shape, half-extents \[m\].
    fn shapes() -> Vec<(OpeningShape, DVec3)> {
        use OpeningShape as S;
        vec![
            (S::Rectangle, DVec3::new(0.6, 0.15, 0.0)),
            (S::Rectangle, DVec3::new(0.6, 0.15, 0.05)),
            (S::Ellipse, DVec3::new(0.2, 0.2, 0.0)),
            (S::Ellipse, DVec3::new(0.3, 0.1, 0.0)),
            (S::Ellipse, DVec3::new(0.2, 0.2, 0.25)),
            (S::Ellipse, DVec3::new(0.3, 0.1, 0.2)),
            (S::Ellipsoid, DVec3::new(0.2, 0.2, 0.2)),
            (S::Ellipsoid, DVec3::new(0.3, 0.1, 0.2)),
            (S::CylinderC0, DVec3::new(0.6, 0.1, 0.1)),
            (S::CylinderC0, DVec3::new(0.6, 0.1, 0.05)),
            (S::CylinderC90, DVec3::new(0.1, 0.5, 0.1)),
            (S::CylinderC90, DVec3::new(0.15, 0.5, 0.08)),
            (S::VerticalEllipseC0, DVec3::new(0.0, 0.2, 0.2)),
            (S::VerticalEllipseC90, DVec3::new(0.3, 0.0, 0.1)),
        ]
    }

    /// Unit directions towards the eye: below, side-on along the axes and
    /// between, above, and oblique.
    fn directions() -> Vec<DVec3> {
        [
            [0.0, 0.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.3, -0.5, -0.8],
            [-0.7, 0.2, 0.4],
            [0.1, 0.2, 1.0],
        ]
        .iter()
        .map(|v| DVec3::from_array(*v).normalize())
        .collect()
    }

    /// Whether the line from far out towards the eye side, `o + t v` with
    /// `v = -d` travelling away from the eye, first meets a luminous
    /// surface of the shape (computed from the solid itself, sharing no
    /// code with [`parts`]); with `closed`, the top of a rectangle or an
    /// ellipse is luminous too.
    fn hits(shape: OpeningShape, h: DVec3, o: DVec3, v: DVec3, closed: bool) -> bool {
        use OpeningShape as S;
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        match shape {
            S::Point => false,
            S::Rectangle | S::Ellipse => {
                let lateral = if shape == S::Rectangle {
                    meet(slab(o, v, x, h.x), slab(o, v, y, h.y))
                } else {
                    ecyl(o, v, (x, h.x), (y, h.y))
                };
                if h.z == 0.0 {
                    // A flat opening at z = 0, luminous towards -z (and +z
                    // when closed): the eye (at -v) must be below it.
                    let inside = lateral.is_some_and(|(t0, t1)| {
                        let t = -o.z / v.z;
                        v.z.abs() > 1e-300 && t0 <= t && t <= t1
                    });
                    return inside && (v.z > 0.0 || closed);
                }
                // The solid from z = -h.z to +h.z; its top is luminous only
                // when closed: else a line entering through the top does
                // not count.
                let Some((t0, _)) = meet(lateral, slab(o, v, z, h.z)) else {
                    return false;
                };
                let p = o + v * t0;
                closed || !((p.z - h.z).abs() < 1e-12 && v.z < 0.0)
            }
            S::Ellipsoid => {
                let (o1, v1) = (o / h, v / h);
                let (qa, qb, qc) = (v1.dot(v1), 2.0 * o1.dot(v1), o1.dot(o1) - 1.0);
                qb * qb - 4.0 * qa * qc >= 0.0
            }
            S::CylinderC0 => meet(slab(o, v, x, h.x), ecyl(o, v, (y, h.y), (z, h.z))).is_some(),
            S::CylinderC90 => meet(slab(o, v, y, h.y), ecyl(o, v, (x, h.x), (z, h.z))).is_some(),
            S::VerticalEllipseC0 => {
                let t = -o.x / v.x;
                let p = o + v * t;
                v.x.abs() > 1e-300 && (p.y / h.y).powi(2) + (p.z / h.z).powi(2) <= 1.0
            }
            S::VerticalEllipseC90 => {
                let t = -o.y / v.y;
                let p = o + v * t;
                v.y.abs() > 1e-300 && (p.x / h.x).powi(2) + (p.z / h.z).powi(2) <= 1.0
            }
        }
    }

    /// The projected luminous area by ray casting: parallel lines along
    /// `-d` through the cell centres of an `n x n` grid over a square that
    /// covers the shape, on the plane normal to `d`.
    fn ray_cast(shape: OpeningShape, h: DVec3, d: DVec3, n: usize, closed: bool) -> f64 {
        let r = h.length() * 1.5;
        let f = crate::sampling::warp::Frame::from_normal(d);
        let mut k = 0usize;
        for i in 0..n {
            for j in 0..n {
                let s = r * (2.0 * (i as f64 + 0.5) / n as f64 - 1.0);
                let t = r * (2.0 * (j as f64 + 0.5) / n as f64 - 1.0);
                // The grid turned by an irrational angle, so that no edge
                // of a rectangle runs along a row of cell centres.
                let (sn, cs) = 0.3f64.sin_cos();
                let q = DVec3::new(cs * s - sn * t, sn * s + cs * t, 0.0);
                let o = f.to_world(q) + d * (4.0 * r);
                k += hits(shape, h, o, -d, closed) as usize;
            }
        }
        k as f64 * (2.0 * r / n as f64).powi(2)
    }

    /// Every shape's projected area from several directions against ray
    /// casting (600 x 600 lines: the grid resolves a smooth outline to far
    /// below 0.5 %, and a 2 % error, a part left out or counted twice shows).
    /// The sphere seen from anywhere is `pi r^2`, by hand.
    #[test]
    fn projected_areas_match_ray_casting() {
        for closed in [false, true] {
            for (shape, h) in shapes() {
                for d in directions() {
                    let a: f64 = parts(shape, h, d, closed).iter().map(|p| p.0).sum();
                    let want = ray_cast(shape, h, d, 600, closed);
                    let scale = 4.0 * h.max_element() * h.max_element();
                    assert!(
                        (a - want).abs() <= 0.005 * want + 1e-6 * scale,
                        "{shape:?} {h} along {d} (closed {closed}): {a} vs ray casting {want}"
                    );
                }
            }
        }
        for d in directions() {
            let a: f64 = parts(OpeningShape::Ellipsoid, DVec3::splat(0.2), d, false)
                .iter()
                .map(|p| p.0)
                .sum();
            assert!((a - PI * 0.04).abs() < 1e-15, "{a}");
        }
    }

    /// The parts' points lie in the luminous outline and fill it uniformly: the area-weighted share of
    /// points on each side of a line through the centre, normal to the
    /// view, matches the ray-cast share of the outline to 1 %.
    #[test]
    fn part_points_cover_the_visible_outline_uniformly() {
        for closed in [false, true] {
            points_cover_the_outline(closed);
        }
    }

    fn points_cover_the_outline(closed: bool) {
        let n = 64;
        for (shape, h) in shapes() {
            for d in directions() {
                let f = crate::sampling::warp::Frame::from_normal(d);
                // A split direction in the view plane.
                let split = (f.to_world(DVec3::X) + f.to_world(DVec3::Y) * 0.37).normalize();
                let (mut total, mut left) = (0.0, 0.0);
                for (a, part) in parts(shape, h, d, closed) {
                    if a <= 0.0 {
                        continue;
                    }
                    let mut k = 0usize;
                    for i in 0..n {
                        for j in 0..n {
                            let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                            let p = part.point(u);
                            // In the outline: the line through p along
                            // the view meets a luminous surface.
                            let o = p + d * (4.0 * h.length());
                            assert!(
                                hits(shape, h, o, -d, closed),
                                "{shape:?} {h} along {d}: {p} not in the outline"
                            );
                            k += (p.dot(split) < 0.0) as usize;
                        }
                    }
                    total += a;
                    left += a * k as f64 / (n * n) as f64;
                }
                let all = ray_cast(shape, h, d, 400, closed);
                if all == 0.0 {
                    assert_eq!(total, 0.0);
                    continue;
                }
                // The ray-cast share on the same side.
                let r = h.length() * 1.01;
                let m = 400;
                let mut kl = 0usize;
                let mut kall = 0usize;
                for i in 0..m {
                    for j in 0..m {
                        let s = r * (2.0 * (i as f64 + 0.5) / m as f64 - 1.0);
                        let t = r * (2.0 * (j as f64 + 0.5) / m as f64 - 1.0);
                        let q = f.to_world(DVec3::new(s, t, 0.0));
                        if hits(shape, h, q + d * (4.0 * r), -d, closed) {
                            kall += 1;
                            kl += (q.dot(split) < 0.0) as usize;
                        }
                    }
                }
                let want = kl as f64 / kall as f64;
                assert!(
                    (left / total - want).abs() < 0.01,
                    "{shape:?} {h} along {d}: share {} vs {want}",
                    left / total
                );
            }
        }
    }

    /// Every part's normal is a unit vector facing the eye, normal to the
    /// surface (orthogonal to the part's tangents, by central differences
    /// of its points) and outward (`n . p >= 0` on these convex shapes
    /// centred on the origin).
    #[test]
    fn part_normals_are_the_surfaces_facing_the_eye() {
        let n = 9;
        for closed in [false, true] {
            for (shape, h) in shapes() {
                for d in directions() {
                    for (a, part) in parts(shape, h, d, closed) {
                        if a <= 0.0 {
                            continue;
                        }
                        for i in 0..n {
                            for j in 0..n {
                                let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                                let (p, nn) = part.point_normal(u);
                                let what = format!("{shape:?} {h} along {d} at {u:?}: n {nn}");
                                assert!((nn.length() - 1.0).abs() < 1e-12, "{what}");
                                assert!(nn.dot(d) > 0.0, "{what} faces away");
                                assert!(nn.dot(p) >= -1e-12, "{what} points inwards at {p}");
                                let e = 1e-6;
                                for k in 0..2 {
                                    let (mut lo, mut hi) = (u, u);
                                    lo[k] -= e;
                                    hi[k] += e;
                                    let t = part.point(hi) - part.point(lo);
                                    assert!(
                                        t.dot(nn).abs() <= 1e-6 * t.length() + 1e-15,
                                        "{what}: tangent {t} along u{k}"
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}
