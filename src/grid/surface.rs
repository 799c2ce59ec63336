//! The flat patch a grid covers: its own rectangle, or a named rectangle,
//! disc or box face of the scene (as the scene file writes them).

use super::invalid;
use crate::scene::SceneError;
use crate::scene::compile::SourceCtx;
use crate::scene::desc::{GridDesc, SceneDesc, SurfaceDesc};
use glam::DVec3;
use toml::Spanned;

/// A flat patch: the rectangle `origin + x u + y v`, `0 <= x <= a`,
/// `0 <= y <= b` (`u`, `v` unit and perpendicular, `u x v = n`), or the
/// disc inscribed in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// Corner \[m\].
    pub origin: DVec3,
    /// Unit first edge direction.
    pub u: DVec3,
    /// Unit second edge direction.
    pub v: DVec3,
    /// Unit normal, `u x v`: the side the points face.
    pub n: DVec3,
    /// Length along `u` \[m\].
    pub a: f64,
    /// Length along `v` \[m\].
    pub b: f64,
    /// A disc: its centre \[m\] and radius \[m\] (inscribed in the square).
    pub disc: Option<(DVec3, f64)>,
}

impl Patch {
    /// The patch less a band of `border` \[m\] along its edges; `None` when
    /// nothing is left.
    pub fn inset(&self, border: f64) -> Option<Patch> {
        let (a, b) = (self.a - 2.0 * border, self.b - 2.0 * border);
        if !(a > 0.0 && b > 0.0) {
            return None;
        }
        Some(Patch {
            origin: self.origin + border * (self.u + self.v),
            a,
            b,
            disc: self.disc.map(|(c, r)| (c, r - border)),
            ..*self
        })
    }

    /// The point at `(x, y)` \[m\] in the patch's frame, if it lies on the patch.
    pub fn point(&self, x: f64, y: f64) -> Option<DVec3> {
        let p = self.origin + x * self.u + y * self.v;
        match self.disc {
            Some((c, r)) if (p - c).length() > r => None,
            _ => Some(p),
        }
    }

    /// Area \[m^2\] of the cell `[x0, x1] x [y0, y1]` (patch frame, m) that
    /// lies on the patch: the whole cell on a rectangle; on a disc, its part
    /// inside the circle (a cell over the rim carried its whole area: a
    /// disc of 1.54 m^2 summed to 1.74). The chord length integrated by
    /// 256 midpoints across a cut cell: within 1e-3 of the cell's area.
    pub fn cell_area(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
        let full = (x1 - x0) * (y1 - y0);
        let Some((c, r)) = self.disc else {
            return full;
        };
        let (cx, cy) = ((c - self.origin).dot(self.u), (c - self.origin).dot(self.v));
        let d2 = |x: f64, y: f64| (x - cx).powi(2) + (y - cy).powi(2);
        if [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
            .iter()
            .all(|&(x, y)| d2(x, y) <= r * r)
        {
            return full;
        }
        const N: usize = 256;
        let dx = (x1 - x0) / N as f64;
        let chord: f64 = (0..N)
            .map(|k| {
                let x = x0 + (k as f64 + 0.5) * dx;
                let h = (r * r - (x - cx).powi(2)).max(0.0).sqrt();
                ((cy + h).min(y1) - (cy - h).max(y0)).max(0.0)
            })
            .sum();
        chord * dx
    }

    /// "2 m x 3 m rectangle" or "disc of radius 0.5 m".
    pub fn describe(&self) -> String {
        match self.disc {
            Some((_, r)) => format!("disc of radius {} m", crate::io::format_number(r)),
            None => format!(
                "{} m x {} m rectangle",
                crate::io::format_number(self.a),
                crate::io::format_number(self.b)
            ),
        }
    }
}

/// A rectangle from `corner`, `edge1`, `edge2` (perpendicular, non-zero),
/// facing `edge1 x edge2`.
fn rectangle(
    corner: &Spanned<crate::scene::desc::Vec3>,
    e1: &Spanned<crate::scene::desc::Vec3>,
    e2: &Spanned<crate::scene::desc::Vec3>,
    flip: bool,
    ctx: &SourceCtx,
) -> Result<Patch, SceneError> {
    let c = DVec3::from(corner.get_ref().0);
    let (u, v) = (DVec3::from(e1.get_ref().0), DVec3::from(e2.get_ref().0));
    for (w, s, f) in [(c, corner, "corner"), (u, e1, "edge1"), (v, e2, "edge2")] {
        if !w.is_finite() {
            return Err(invalid(ctx, s.span(), f, "must be finite"));
        }
    }
    for (w, s, f) in [(u, e1, "edge1"), (v, e2, "edge2")] {
        if w.length() <= 0.0 {
            return Err(invalid(ctx, s.span(), f, "has zero length"));
        }
    }
    if u.dot(v).abs() > 1e-9 * u.length() * v.length() {
        return Err(invalid(
            ctx,
            e2.span(),
            "edge2",
            "a grid needs a rectangle: `edge1` and `edge2` must be perpendicular",
        ));
    }
    let (a, b) = (u.length(), v.length());
    let (mut u, mut v) = (u / a, v / b);
    let (mut a, mut b) = (a, b);
    if flip {
        std::mem::swap(&mut u, &mut v);
        std::mem::swap(&mut a, &mut b);
    }
    Ok(Patch {
        origin: c,
        u,
        v,
        n: u.cross(v).normalize(),
        a,
        b,
        disc: None,
    })
}

/// The grid's own rectangle (`what` names the grid kind in messages).
pub(super) fn patch_of_edges(
    g: &GridDesc,
    ctx: &SourceCtx,
    what: &str,
) -> Result<Patch, SceneError> {
    let missing = |f: &str| {
        invalid(
            ctx,
            g.name.span(),
            f,
            format!("a {what} needs `corner`, `edge1` and `edge2`: `{f}` is missing"),
        )
    };
    let corner = g.corner.as_ref().ok_or_else(|| missing("corner"))?;
    let e1 = g.edge1.as_ref().ok_or_else(|| missing("edge1"))?;
    let e2 = g.edge2.as_ref().ok_or_else(|| missing("edge2"))?;
    rectangle(corner, e1, e2, false, ctx)
}

/// Box faces by name, with their axis and end (0: `min`, 1: `max`).
const FACES: [(&str, usize, usize); 6] = [
    ("x_min", 0, 0),
    ("x_max", 0, 1),
    ("y_min", 1, 0),
    ("y_max", 1, 1),
    ("z_min", 2, 0),
    ("z_max", 2, 1),
];

/// The surfaces of `scene` named `n`.
pub(super) fn named<'a>(scene: &'a SceneDesc, n: &str) -> Vec<&'a SurfaceDesc> {
    scene
        .surface
        .iter()
        .map(|s| s.get_ref())
        .filter(|s| s.name.as_ref().is_some_and(|m| m.get_ref() == n))
        .collect()
}

/// The patch of a named surface: a rectangle or disc by its name, a box
/// face as `"BOX.FACE"`. Its normal is the surface's reflecting side (the
/// front of a two-sided one).
pub(super) fn patch_of_surface(
    scene: &SceneDesc,
    name: &Spanned<String>,
    ctx: &SourceCtx,
) -> Result<Patch, SceneError> {
    let wanted = name.get_ref().as_str();
    let named = |n: &str| named(scene, n);
    let err = |m: String| invalid(ctx, name.span(), "surface", m);
    let found = named(wanted);
    if !found.is_empty()
        && let Some((base, face)) = wanted.rsplit_once('.')
        && FACES.iter().any(|f| f.0 == face)
        && named(base).iter().any(|b| b.kind.get_ref() == "box")
    {
        return Err(err(format!(
            "`{wanted}` names both a surface and face `{face}` of box `{base}`: rename the \
             surface (a `.` in a surface's name is read as a box face)"
        )));
    }
    if found.len() > 1 {
        return Err(err(format!(
            "{} surfaces are named `{wanted}`; a grid needs a unique name",
            found.len()
        )));
    }
    if let Some(s) = found.first() {
        return match s.kind.get_ref().as_str() {
            "rectangle" => {
                let field = |v: &Option<Spanned<crate::scene::desc::Vec3>>, f: &str| {
                    v.clone()
                        .ok_or_else(|| err(format!("rectangle `{wanted}` has no `{f}`")))
                };
                let flip = s.sides.as_ref().is_some_and(|x| x.get_ref() == "back");
                rectangle(
                    &field(&s.corner, "corner")?,
                    &field(&s.edge1, "edge1")?,
                    &field(&s.edge2, "edge2")?,
                    flip,
                    ctx,
                )
                .map_err(|_| {
                    err(format!(
                        "rectangle `{wanted}` is a parallelogram: a grid needs perpendicular edges"
                    ))
                })
            }
            "disc" => {
                let (Some(c), Some(n), Some(r)) = (&s.center, &s.normal, &s.radius) else {
                    return Err(err(format!(
                        "disc `{wanted}` lacks `center`, `normal` or `radius`"
                    )));
                };
                let c = DVec3::from(c.get_ref().0);
                let n = DVec3::from(n.get_ref().0);
                let r = *r.get_ref();
                if !(c.is_finite() && n.is_finite() && n.length() > 0.0 && r.is_finite() && r > 0.0)
                {
                    return Err(err(format!(
                        "disc `{wanted}` has a bad `center`, `normal` or `radius`"
                    )));
                }
                let mut n = n.normalize();
                if s.sides.as_ref().is_some_and(|x| x.get_ref() == "back") {
                    n = -n;
                }
                let f = crate::sampling::warp::Frame::from_normal(n);
                Ok(Patch {
                    origin: c - r * (f.s + f.t),
                    u: f.s,
                    v: f.t,
                    n,
                    a: 2.0 * r,
                    b: 2.0 * r,
                    disc: Some((c, r)),
                })
            }
            "box" => Err(err(format!(
                "`{wanted}` is a box: name one of its faces, e.g. `{wanted}.z_max` (x_min, x_max, y_min, y_max, z_min, z_max)"
            ))),
            other => Err(err(format!(
                "`{wanted}` is a {other}: a grid lies on a rectangle, a disc or a box face (planes are infinite)"
            ))),
        };
    }
    // A box face: "BOX.FACE".
    if let Some((base, face)) = wanted.rsplit_once('.')
        && let [b] = named(base)[..]
        && b.kind.get_ref() == "box"
    {
        let Some(&(_, k, end)) = FACES.iter().find(|f| f.0 == face) else {
            return Err(err(format!(
                "box `{base}` has no face `{face}` (x_min, x_max, y_min, y_max, z_min, z_max)"
            )));
        };
        let (Some(lo), Some(hi)) = (&b.min, &b.max) else {
            return Err(err(format!("box `{base}` lacks `min` or `max`")));
        };
        let (lo, hi) = (DVec3::from(lo.get_ref().0), DVec3::from(hi.get_ref().0));
        let outward = b.normals.as_ref().is_some_and(|x| x.get_ref() == "outward");
        let axis = |i: usize| DVec3::AXES[i];
        // Outward: the max face faces +axis; inward (a room): the min face does.
        let n = if (end == 1) == outward {
            axis(k)
        } else {
            -axis(k)
        };
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let (mut u, mut v) = (axis(i), axis(j));
        let (mut a, mut bb) = (hi[i] - lo[i], hi[j] - lo[j]);
        if u.cross(v).dot(n) < 0.0 {
            std::mem::swap(&mut u, &mut v);
            std::mem::swap(&mut a, &mut bb);
        }
        if !(lo.is_finite() && hi.is_finite() && a > 0.0 && bb > 0.0 && hi[k] > lo[k]) {
            return Err(err(format!("box `{base}` has a bad `min` or `max`")));
        }
        let mut origin = lo;
        origin[k] = if end == 1 { hi[k] } else { lo[k] };
        return Ok(Patch {
            origin,
            u,
            v,
            n,
            a,
            b: bb,
            disc: None,
        });
    }
    let names: Vec<String> = scene
        .surface
        .iter()
        .filter_map(|s| {
            s.get_ref()
                .name
                .as_ref()
                .map(|n| format!("`{}`", n.get_ref()))
        })
        .collect();
    Err(err(format!(
        "no surface named `{wanted}` (named surfaces: {}; a box face is `BOX.z_max` and so on)",
        if names.is_empty() {
            "none".to_string()
        } else {
            names.join(", ")
        }
    )))
}
