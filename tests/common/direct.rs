//! An independent reference for the first order (light straight from the
//! sources), written from the definitions and sharing no code with lumest's
//! estimators, its `Light` methods or its ray-shape intersection. Only shape
//! data comes from lumest where a test's scene is built by it: the corners
//! of a mesh's triangles and the radius function of a spherical-harmonic
//! object ([`Occluder::Star`]); [`read_obj`] reads an OBJ file itself.
//!
//! - **Blocking**: an occluder blocks the open segment from a receiver to a
//!   light point when the segment meets it at a parameter `t` in
//!   `(EPS, 1 - EPS)`; end points lying on a surface are never shadowed by
//!   it. Each primitive has its own ray-primitive test written here:
//!   half-space sign for infinite planes, the quadratic for spheres, slabs
//!   for boxes, plane hit plus containment for discs and parallelograms,
//!   barycentric coordinates for triangles, and a dense march against the
//!   radius function for star-shaped (spherical-harmonic) objects.
//! - **Point light** of intensity `I` \[cd\] at `q`: `E = I cos(theta) / d^2`
//!   \[lx\] when `q` lies above the receiver's horizon and nothing blocks.
//! - **Sphere light** (centre `c`, radius `r`, uniform luminance
//!   `L = I / (pi r^2)` [cd/m^2]): `E = L int_cone max(0, n . w) dw`. Wholly
//!   above the horizon this is `I cos(beta) / D^2`. The reference integrates
//!   the visible solid angle by quadrature ([`sphere_cone_quadrature`]: the
//!   ring integral in closed form, 64 Gauss-Legendre points in the polar
//!   angle), checked against the closed form of the configuration factor
//!   from a tilted plane element to a sphere (Howell's catalogue,
//!   "differential planar element of any tilt to sphere"),
//!   `E = (I / r^2) F` ([`sphere_illuminance`]), which cancels for slivers
//!   just above the horizon.
//! - **Luminance** of once-reflected light at a sub-point with BRDF `f` and
//!   unit world direction `wo` to the observer: `sum_l f(wi_l, wo) E_l` for
//!   point lights and `L int_cone f(w, wo) max(0, n . w) dw` for sphere
//!   lights (quadrature over the visible solid angle).
//! - **Phong BRDF** (the documented definition of `Material::Phong`),
//!   evaluated in world coordinates: `kd / pi + ks (n + 2) / (2 pi)
//!   max(0, cos alpha)^n`, `cos alpha = 2 (wi . N)(wo . N) - wi . wo` (the
//!   cosine between `wo` and the mirror direction of `wi` about the normal
//!   `N`), zero unless both directions lie above the surface.

use gauss_quad::legendre::GaussLegendre;
use glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// Relative end-point exclusion of a segment (fraction of its length).
pub const EPS: f64 = 1e-9;

/// An opaque shape that can block a segment.
pub enum Occluder {
    /// Infinite plane through `p` with normal `n`: blocks when the end
    /// points lie strictly on opposite sides.
    Plane { p: DVec3, n: DVec3 },
    /// Sphere surface.
    Sphere { c: DVec3, r: f64 },
    /// Axis-aligned box surface.
    Box { lo: DVec3, hi: DVec3 },
    /// Disc of centre `c`, unit normal `n`, radius `r`.
    Disc { c: DVec3, n: DVec3, r: f64 },
    /// Parallelogram `o + u e1 + v e2`, `u, v` in `[0, 1]`.
    Parallelogram { o: DVec3, e1: DVec3, e2: DVec3 },
    /// Triangle.
    Triangle([DVec3; 3]),
    /// Triangles inside the ball of centre `c` and radius `r` (a segment
    /// that misses the ball meets none of them).
    Mesh {
        c: DVec3,
        r: f64,
        tris: Vec<Occluder>,
    },
    /// Star-shaped object: a point `q` is inside when
    /// `|q - c| < scale * radius(rot^T (q - c))`.
    Star {
        c: DVec3,
        rot: DMat3,
        scale: f64,
        radius: Box<dyn Fn(DVec3) -> f64>,
    },
}

impl Occluder {
    /// Whether the open segment `a b` meets this occluder (see the module docs).
    pub fn blocks(&self, a: DVec3, b: DVec3) -> bool {
        let d = b - a;
        let inside = |t: f64| t > EPS && t < 1.0 - EPS;
        match self {
            Occluder::Plane { p, n } => {
                let (da, db) = ((a - *p).dot(*n), (b - *p).dot(*n));
                let tol = 1e-12 * (a.abs().max_element() + b.abs().max_element() + 1.0);
                (da > tol && db < -tol) || (da < -tol && db > tol)
            }
            Occluder::Sphere { c, r } => {
                // |a + t d - c|^2 = r^2.
                let oc = a - *c;
                let (qa, qb, qc) = (d.dot(d), 2.0 * oc.dot(d), oc.dot(oc) - r * r);
                let disc = qb * qb - 4.0 * qa * qc;
                if disc <= 0.0 {
                    return false;
                }
                let s = disc.sqrt();
                inside((-qb - s) / (2.0 * qa)) || inside((-qb + s) / (2.0 * qa))
            }
            Occluder::Box { lo, hi } => {
                let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
                for k in 0..3 {
                    if d[k] == 0.0 {
                        if a[k] < lo[k] || a[k] > hi[k] {
                            return false;
                        }
                        continue;
                    }
                    let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
                    t0 = t0.max(u.min(v));
                    t1 = t1.min(u.max(v));
                }
                t0 <= t1 && (inside(t0) || inside(t1))
            }
            Occluder::Disc { c, n, r } => match plane_hit(a, d, *c, *n) {
                Some(t) if inside(t) => (a + d * t - *c).length() < *r,
                _ => false,
            },
            Occluder::Parallelogram { o, e1, e2 } => {
                let n = e1.cross(*e2).normalize();
                match plane_hit(a, d, *o, n) {
                    Some(t) if inside(t) => {
                        let q = a + d * t - *o;
                        // Solve q = u e1 + v e2 by the 2 x 2 Gram system.
                        let (g11, g12, g22) = (e1.dot(*e1), e1.dot(*e2), e2.dot(*e2));
                        let (r1, r2) = (q.dot(*e1), q.dot(*e2));
                        let det = g11 * g22 - g12 * g12;
                        let u = (r1 * g22 - r2 * g12) / det;
                        let v = (r2 * g11 - r1 * g12) / det;
                        (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)
                    }
                    _ => false,
                }
            }
            Occluder::Triangle([p0, p1, p2]) => {
                let n = (*p1 - *p0).cross(*p2 - *p0);
                match plane_hit(a, d, *p0, n.normalize()) {
                    Some(t) if inside(t) => {
                        let q = a + d * t;
                        // Same orientation of the three sub-triangles.
                        let s0 = (*p1 - *p0).cross(q - *p0).dot(n);
                        let s1 = (*p2 - *p1).cross(q - *p1).dot(n);
                        let s2 = (*p0 - *p2).cross(q - *p2).dot(n);
                        s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0
                    }
                    _ => false,
                }
            }
            Occluder::Mesh { c, r, tris } => {
                let t = ((*c - a).dot(d) / d.dot(d)).clamp(0.0, 1.0);
                (a + d * t - *c).length() <= *r && tris.iter().any(|o| o.blocks(a, b))
            }
            Occluder::Star {
                c,
                rot,
                scale,
                radius,
            } => {
                // March 20,000 steps; the decision must be clear: the
                // deepest point is at least 1e-3 of the size inside, or
                // the closest point at least that far outside.
                let n = 20_000;
                let mut deepest = f64::NEG_INFINITY;
                for k in 1..n {
                    let t = k as f64 / n as f64;
                    let q = a + d * t - *c;
                    let depth = scale * radius(rot.transpose() * q) - q.length();
                    deepest = deepest.max(depth);
                }
                assert!(
                    deepest.abs() > 1e-3 * scale,
                    "star-shaped occluder: undecidable segment (margin {deepest})"
                );
                deepest > 0.0
            }
        }
    }
}

/// Parameter `t` where the line `a + t d` meets the plane through `p` with
/// normal `n`; `None` when parallel.
fn plane_hit(a: DVec3, d: DVec3, p: DVec3, n: DVec3) -> Option<f64> {
    let den = n.dot(d);
    (den != 0.0).then(|| n.dot(p - a) / den)
}

/// Whether any occluder blocks the open segment `a b`.
pub fn blocked(occ: &[Occluder], a: DVec3, b: DVec3) -> bool {
    occ.iter().any(|o| o.blocks(a, b))
}

/// A light source as the reference sees it.
#[derive(Clone, Copy, Debug)]
pub enum RefLight {
    /// Isotropic point: position \[m\], intensity \[cd\].
    Point { q: DVec3, i: f64 },
    /// Lambertian sphere: centre \[m\], radius \[m\], intensity \[cd\].
    Sphere { c: DVec3, r: f64, i: f64 },
}

/// What a reference receiver measures.
#[derive(Clone, Copy, Debug)]
pub enum RefResponse {
    /// Illuminance \[lx\].
    Illuminance,
    /// Luminance [cd/m^2] of a Phong (or, with `ks = 0`, Lambertian) surface
    /// towards the unit world direction `wo`.
    Phong { kd: f64, ks: f64, n: f64, wo: DVec3 },
}

/// The Phong BRDF [1/sr] in world coordinates for the surface normal `nn`
/// (module docs).
pub fn phong(kd: f64, ks: f64, n: f64, nn: DVec3, wi: DVec3, wo: DVec3) -> f64 {
    let (ci, co) = (wi.dot(nn), wo.dot(nn));
    if ci <= 0.0 || co <= 0.0 {
        return 0.0;
    }
    let cos_alpha = 2.0 * ci * co - wi.dot(wo);
    let spec = if cos_alpha > 0.0 {
        ks * (n + 2.0) / (2.0 * PI) * cos_alpha.powf(n)
    } else {
        0.0
    };
    kd / PI + spec
}

impl RefResponse {
    /// Response to light arriving from unit direction `wi` at a receiver
    /// with unit normal `nn`: 1, or the BRDF.
    pub fn weight(&self, nn: DVec3, wi: DVec3) -> f64 {
        match *self {
            RefResponse::Illuminance => 1.0,
            RefResponse::Phong { kd, ks, n, wo } => phong(kd, ks, n, nn, wi, wo),
        }
    }
}

/// Illuminance \[lx\] from a sphere light (centre `c`, radius `r`, intensity
/// `i`) at `x` with unit normal `n`, horizon included, unoccluded: the
/// closed-form configuration factor of a tilted element to a sphere.
pub fn sphere_illuminance(c: DVec3, r: f64, i: f64, x: DVec3, n: DVec3) -> f64 {
    let dv = c - x;
    let dist = dv.length();
    let h = dist / r;
    let cphi = n.dot(dv) / dist;
    let f = if cphi >= 1.0 / h {
        cphi / (h * h)
    } else if cphi <= -1.0 / h {
        0.0
    } else {
        let sphi = (1.0 - cphi * cphi).sqrt();
        let g = (h * h - 1.0).sqrt();
        0.5 - (g / (h * sphi)).min(1.0).asin() / PI
            + (cphi * (-g * cphi / sphi).clamp(-1.0, 1.0).acos()
                - g * (1.0 - h * h * cphi * cphi).max(0.0).sqrt())
                / (PI * h * h)
    };
    i / (r * r) * f
}

/// `int_cone w(dir) max(0, n . dir) d(dir)` \[sr\] over the cone a sphere of
/// radius `r` centred at `c` subtends from `x`, clipped at the horizon of
/// the unit normal `n`, by quadrature in polar coordinates `(theta, phi)`
/// about `n`: the cone cuts each ring of polar angle `theta` in an interval
/// `|phi| <= phi0(theta)` known in closed form, and the `theta` range is
/// split where `phi0` has square-root end points, each piece smoothed by
/// `theta = u + (v - u) s^2 (3 - 2 s)`. `q`: Gauss-Legendre points per
/// piece in `theta` and per ring in `phi`. With `w = None` the ring
/// integral `2 phi0 cos(theta)` is exact and only `theta` is integrated.
pub fn sphere_cone_quadrature(
    c: DVec3,
    r: f64,
    x: DVec3,
    n: DVec3,
    w: Option<&dyn Fn(DVec3) -> f64>,
    q: usize,
) -> f64 {
    let dv = c - x;
    let dist = dv.length();
    let a = dv / dist;
    let sa = r / dist;
    let ca = (1.0 - sa * sa).sqrt();
    let alpha = sa.asin();
    let cb = a.dot(n).clamp(-1.0, 1.0);
    let beta = cb.acos();
    let sb = (1.0 - cb * cb).sqrt();
    // Tangent frame: t1 towards the cone axis.
    let t1 = {
        let p = a - n * cb;
        if p.length() > 1e-12 {
            p.normalize()
        } else {
            n.any_orthonormal_vector()
        }
    };
    let t2 = n.cross(t1);
    let phi0 = |theta: f64| -> f64 {
        let (st, ct) = theta.sin_cos();
        if sb * st < 1e-300 {
            return if ct * cb >= ca { PI } else { 0.0 };
        }
        let cmin = (ca - ct * cb) / (st * sb);
        if cmin <= -1.0 {
            PI
        } else if cmin >= 1.0 {
            0.0
        } else {
            cmin.acos()
        }
    };
    let rule = GaussLegendre::new(std::num::NonZeroUsize::new(q).unwrap());
    let ring = |theta: f64| -> f64 {
        let p0 = phi0(theta);
        if p0 == 0.0 {
            return 0.0;
        }
        let (st, ct) = theta.sin_cos();
        match w {
            None => 2.0 * p0 * ct * st,
            Some(w) => {
                rule.integrate(-p0, p0, |phi: f64| {
                    let (sp, cp) = phi.sin_cos();
                    w(t1 * (st * cp) + t2 * (st * sp) + n * ct)
                }) * ct
                    * st
            }
        }
    };
    let lo = (beta - alpha).max(0.0);
    let hi = (beta + alpha).min(PI / 2.0);
    if hi <= lo {
        return 0.0;
    }
    let mut cuts = vec![lo];
    if beta < alpha && alpha - beta < hi {
        cuts.push(alpha - beta);
    }
    cuts.push(hi);
    let mut sum = 0.0;
    for k in cuts.windows(2) {
        let (u, v) = (k[0], k[1]);
        sum += rule.integrate(0.0, 1.0, |s: f64| {
            let th = u + (v - u) * s * s * (3.0 - 2.0 * s);
            ring(th) * (v - u) * 6.0 * s * (1.0 - s)
        });
    }
    sum
}

/// The reference first order at a receiver (`x`, unit normal `n`,
/// response `resp`) from `lights` with `occ` blocking; a sphere light is
/// seen when nothing blocks the segment to its centre (the scenes that
/// allow sphere lights hold only infinite planes, with each sphere light
/// wholly on one side of each, so its centre decides). `q`: quadrature
/// points for sphere lights seen by a luminance receiver.
pub fn first_order(
    lights: &[RefLight],
    occ: &[Occluder],
    x: DVec3,
    n: DVec3,
    resp: RefResponse,
    q: usize,
) -> f64 {
    first_order_with(lights, &|a, b| blocked(occ, a, b), x, n, resp, q)
}

/// [`first_order`] with any blocking rule `block(a, b)` for the open segment `a b`.
pub fn first_order_with(
    lights: &[RefLight],
    block: &dyn Fn(DVec3, DVec3) -> bool,
    x: DVec3,
    n: DVec3,
    resp: RefResponse,
    q: usize,
) -> f64 {
    let mut sum = 0.0;
    for l in lights {
        match *l {
            RefLight::Point { q: p, i } => {
                let dv = p - x;
                let cos = n.dot(dv);
                if cos > 0.0 && !block(x, p) {
                    let d2 = dv.dot(dv);
                    let wi = dv / d2.sqrt();
                    sum += resp.weight(n, wi) * i * cos / (d2 * d2.sqrt());
                }
            }
            RefLight::Sphere { c, r, i } => {
                if block(x, c) {
                    continue;
                }
                let lum = i / (PI * r * r);
                sum += match resp {
                    RefResponse::Illuminance => lum * sphere_cone_quadrature(c, r, x, n, None, 64),
                    RefResponse::Phong { .. } => {
                        let w = |wi: DVec3| resp.weight(n, wi);
                        lum * sphere_cone_quadrature(c, r, x, n, Some(&w), q)
                    }
                };
            }
        }
    }
    sum
}

/// Triangles (corners) with their bounding ball as one occluder.
pub fn triangle_mesh(tris: &[[DVec3; 3]]) -> Occluder {
    let n = (3 * tris.len()) as f64;
    let c = tris.iter().flatten().fold(DVec3::ZERO, |a, &p| a + p) / n;
    let r = tris
        .iter()
        .flatten()
        .map(|&p| (p - c).length())
        .fold(0.0, f64::max)
        * (1.0 + 1e-9);
    Occluder::Mesh {
        c,
        r,
        tris: tris.iter().map(|&t| Occluder::Triangle(t)).collect(),
    }
}

/// Vertices and triangles of a Wavefront OBJ text (`v x y z` and
/// `f i j k` lines, 1-based indices; other lines ignored).
pub fn read_obj(text: &str) -> Vec<[DVec3; 3]> {
    let mut v = Vec::new();
    let mut tris = Vec::new();
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.map(|x| x.parse().unwrap()).collect();
                v.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let k: Vec<usize> = it
                    .map(|x| x.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                tris.push([v[k[0]], v[k[1]], v[k[2]]]);
            }
            _ => {}
        }
    }
    tris
}

/// The triangles of a lumest mesh as occluders (corner positions only).
pub fn mesh_triangles(m: &lumest::geometry::mesh::Mesh) -> Vec<Occluder> {
    (0..m.triangle_count() as u32)
        .map(|t| Occluder::Triangle(m.corners(t)))
        .collect()
}
