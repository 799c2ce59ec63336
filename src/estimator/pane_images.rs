//! Mirror images of point-like lights and of a collimated sun in glass
//! panes: the direct light a receiver gets by one specular reflection.
//!
//! A point source at `l` seen in a pane (plane `P`, front normal `n`) looks
//! like a source at the mirror image `l'` of `l` in `P`: the reflected ray
//! from `l` through the pane point `m` to the receiver `x` has the length
//! `|x - l'|`, and leaves the source in the direction `m - l`. Mirroring the
//! receiver instead (`x'`, normal `n'`) keeps the source where it is: the
//! reflected illuminance at `x` is
//!
//! `E = R(cos) T_other I(m - l) max(0, n' . (l - x')) / |l - x'|^2`,
//!
//! exactly the source's own closed form at the mirrored receiver, times the
//! pane's reflectance `R` at the incidence angle and the transmittance of
//! any other pane on the two legs. The path exists when `l` and `x` lie on
//! the same side of the pane's plane, the segment from `x` to `l'` crosses
//! the pane inside its outline, and neither leg is blocked. A collimated
//! sun (unit direction of travel `d`) is the limit: the receiver sees it
//! along the mirror image of `-d`, through the pane, with `E = R E_n
//! max(0, n' . (-d))`.
//!
//! Only one reflection is counted: an image in a second pane carries
//! `R^2` (about 0.6 % for clear glass) and is left out.

use crate::geometry::Ray;
use crate::light::Light;
use crate::scene::Scene;
use glam::DVec3;

/// Mirror image of point `p` in the plane through `o` with unit normal `n`.
#[inline]
fn mirror_point(p: DVec3, o: DVec3, n: DVec3) -> DVec3 {
    p - n * (2.0 * n.dot(p - o))
}

/// Mirror image of direction `v` in a plane of unit normal `n`.
#[inline]
fn mirror_dir(v: DVec3, n: DVec3) -> DVec3 {
    v - n * (2.0 * n.dot(v))
}

/// A light's closed form at a receiver `(x, n)` whose response is applied
/// to the incoming direction mapped by the third argument.
pub type ClosedForm<'a> = dyn Fn(DVec3, DVec3, &dyn Fn(DVec3) -> DVec3) -> f64 + 'a;

/// Direct light [lx, or the response's unit] that light `k` sends to the
/// receiver at `x` (unit normal `n`) by one reflection in each of the
/// scene's panes. `closed` is the light's closed form at a receiver
/// `(x', n')` with response `w(wi')` (for the mirrored receiver, `w` is
/// applied to the mirrored direction); only point-like lights and a
/// collimated sun have images (0 otherwise).
pub fn image_direct(scene: &Scene, k: usize, x: DVec3, n: DVec3, closed: &ClosedForm) -> f64 {
    let l = &scene.lights[k];
    let mut total = 0.0;
    for (i, pane) in scene.panes().iter().enumerate() {
        let pl = pane.plane();
        let (o, pn) = (pl.p, pl.n);
        let x_img = mirror_point(x, o, pn);
        let n_img = mirror_dir(n, pn);
        let unmirror = move |w: DVec3| mirror_dir(w, pn);
        // The direction the path arrives at the pane in, and the
        // transmittance of other panes on its two legs.
        let (d_in, glass) = match l {
            Light::Distant(dl) if dl.collimated() => {
                // Looking from x along the mirrored sun direction.
                let look = mirror_dir(-dl.d, pn);
                let ray = Ray { o: x, d: look };
                let t_opaque = scene.first_hit_from(x, look).map_or(f64::INFINITY, |h| h.t);
                let Some(t) = pane_hit_along(scene, i, &ray, t_opaque) else {
                    continue;
                };
                let m = x + look * t;
                // From the pane towards the sun: nothing opaque.
                if scene.first_hit_from(m, -dl.d).is_some() {
                    continue;
                }
                let glass =
                    scene.pane_transmittance(x, m) * scene.pane_transmittance_ray(m, -dl.d, false);
                (dl.d, glass)
            }
            _ if l.is_point_like() => {
                let lp = l.position();
                let (sl, sx) = (pl.side(lp), pl.side(x));
                if sl == 0 || sl != sx {
                    continue;
                }
                let l_img = mirror_point(lp, o, pn);
                let (dx, dl) = (pl.signed_distance(x), pl.signed_distance(l_img));
                let m = pl.project(x + (l_img - x) * (dx / (dx - dl)));
                if !pane_holds(scene, i, m) {
                    continue;
                }
                if scene.behind_light_surface(k, m)
                    || !scene.visible(lp, None, m)
                    || !scene.visible(m, None, x)
                {
                    continue;
                }
                let glass = scene.pane_transmittance(lp, m) * scene.pane_transmittance(m, x);
                ((m - lp).normalize(), glass)
            }
            _ => continue,
        };
        let (r, _) = pane.glass.reflect_transmit(d_in.dot(pn));
        if r * glass > 0.0 {
            total += r * glass * closed(x_img, n_img, &unmirror);
        }
    }
    total
}

/// Ray parameter where `ray` meets pane `i` in `(0, t_max)`.
fn pane_hit_along(scene: &Scene, i: usize, ray: &Ray, t_max: f64) -> Option<f64> {
    let pl = scene.panes()[i].plane();
    if pl.side(ray.o) == 0 {
        return None;
    }
    let t = pl.intersect(ray, t_max)?;
    pane_holds(scene, i, ray.o + ray.d * t).then_some(t)
}

/// Whether point `m` of pane `i`'s plane lies on the pane.
fn pane_holds(scene: &Scene, i: usize, m: DVec3) -> bool {
    scene.panes()[i].contains(m)
}
