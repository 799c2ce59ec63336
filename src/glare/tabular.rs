//! The tabular method of CIE 117-1995 for standard rooms: the rating of a
//! luminaire in a regular array, as luminaire makers publish it (the UGR
//! table, [`ugr_table`]), and an independent check of `lumest glare`.
//!
//! The standard room: a floor `across x along` \[m\] (CIE 117's `X`, across
//! the line of sight, and `Y`, along it), luminaires in a regular grid in
//! the ceiling plane at height `H` above the eye (the outer rows half a
//! spacing from the walls), the observer at the middle of the wall `along
//! = 0` looking horizontally into the room, reflectances of ceiling, walls
//! and floor. The box whose surfaces inter-reflect reaches from the floor
//! to the ceiling; in the published tables ([`ugr_table`]) its floor is
//! the eye plane, standing for the floor cavity below it with that
//! cavity's effective reflectance (the tables' 0.2), so that its walls are
//! `H` high and a table depends on the room only through `X / H`, `Y / H`
//! and the spacing over `H`, as tables are printed (a user finds `H` as
//! the luminaires' height above the floor less the eye's, 1.2 m seated or
//! 1.7 m standing; tested). A room with a real floor below the eye (the
//! checks against `lumest glare` in a scene) sets the eye's height above
//! it. The rating uses the same terms `L^2 omega / p^2` as
//! [`crate::glare`] (the luminance and the projected luminous area of
//! [`LuminousArea`], Guth's [`position_index`]; no obstruction in an empty
//! room) over every luminaire of the room, and the background of the
//! tabular method: `L_b = E_W / pi` with `E_W` the
//! **average indirect illuminance on the walls**. That comes from the
//! luminaires' direct flux onto floor, walls and ceiling and the
//! inter-reflection of the three surfaces, each treated as uniform (the
//! flux-transfer model of the tables; written here from the box's exact
//! view factors, not from CIE 190's equations, whose text was not used).
//! The Monte Carlo estimate of `lumest glare` uses the indirect
//! illuminance at the eye itself, so the two differ by how far the eye's
//! background is from the walls' average: the tables' own approximation.
//!
//! The direct flux on the floor is exact up to quadrature for any
//! intensity distribution: the sum over the luminaire grid of the integral
//! over the floor is one integral over the offset `u` between a luminaire
//! and a floor point, weighted by how many luminaire-floor pairs have that
//! offset, which is `(n_x - |k|) (n_y - |l|)` on the spacing-sized cell
//! `(k, l)` of offsets ([`StandardRoom::direct_flux`]).

use super::{LuminousArea, in_position_field, position_index};
use crate::light::{Goniometric, LuminaireFrame};
use crate::math::quadrature::CompensatedSum;
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::OnceLock;

/// A luminaire as the tabular method needs it, in the room's frame: the
/// line of sight along `+x`, across it `y`, up `+z`.
pub trait TableLuminaire {
    /// Intensity \[cd\] towards unit direction `w` (from the luminaire).
    fn intensity(&self, w: DVec3) -> f64;
    /// Its luminous area [m^2] projected on the plane normal to `w`.
    fn projected_area(&self, w: DVec3) -> f64;
}

/// A luminaire from a photometric file, turned in the ceiling by `frame`.
pub struct FileLuminaire<'a> {
    /// The intensity distribution.
    pub dist: &'a Goniometric,
    /// Its luminous parts.
    pub area: &'a LuminousArea,
    /// Its axes in the room.
    pub frame: LuminaireFrame,
}

impl TableLuminaire for FileLuminaire<'_> {
    fn intensity(&self, w: DVec3) -> f64 {
        self.dist.intensity_world(&self.frame, w)
    }
    fn projected_area(&self, w: DVec3) -> f64 {
        self.area.projected(w, &self.frame)
    }
}

/// How the observer looks at the luminaires.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Across the luminaires: the line of sight at right angles to their
    /// length, which photometric files put along C0-C180 (IES LM-63 and
    /// EULUMDAT alike), so the line of sight runs along C90-C270.
    Crosswise,
    /// Along the luminaires: the line of sight along C0-C180.
    Endwise,
}

impl View {
    /// The luminaire's axes in the room's frame (line of sight `+x`).
    pub fn frame(self) -> LuminaireFrame {
        match self {
            View::Endwise => LuminaireFrame::DEFAULT,
            View::Crosswise => LuminaireFrame {
                x: DVec3::Y,
                y: DVec3::NEG_X,
                z: DVec3::Z,
            },
        }
    }
}

/// A standard room with a grid of identical ceiling luminaires.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StandardRoom {
    /// Room dimension across the line of sight \[m\] (CIE 117's `X`).
    pub across: f64,
    /// Room dimension along the line of sight \[m\] (CIE 117's `Y`).
    pub along: f64,
    /// Eye height above the floor of the inter-reflecting box \[m\]: 0 in
    /// the published tables (the floor cavity collapsed into the eye
    /// plane), 1.2 for a seated eye above a real floor.
    pub eye: f64,
    /// Height of the luminaire (ceiling) plane above the eye \[m\].
    pub h: f64,
    /// Luminaire spacing \[m\] in both directions (rounded per direction to
    /// a whole number of luminaires, at least one).
    pub spacing: f64,
    /// Reflectances of ceiling, walls and floor.
    pub rho: [f64; 3],
}

/// The view factor between two directly opposed parallel `a x b`
/// rectangles at distance `c` (Hottel; Howell's catalogue C-11).
pub fn view_factor_parallel(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (x2, y2) = (x * x, y * y);
    let s = (((1.0 + x2) * (1.0 + y2)) / (1.0 + x2 + y2)).sqrt().ln()
        + x * (1.0 + y2).sqrt() * (x / (1.0 + y2).sqrt()).atan()
        + y * (1.0 + x2).sqrt() * (y / (1.0 + x2).sqrt()).atan()
        - x * x.atan()
        - y * y.atan();
    2.0 * s / (PI * x * y)
}

/// The result of the tabular method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tabular {
    /// `sum L^2 omega / p^2` over the room's luminaires [(cd/m^2)^2 sr].
    pub sum: f64,
    /// Average indirect illuminance on the walls \[lx\].
    pub e_wall_ind: f64,
    /// The rating `8 log10(0.25 pi sum / E_W)`.
    pub ugr: f64,
}

/// The luminaires' direct flux \[lm\] on the room's surfaces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectFlux {
    /// On the ceiling: the upward flux (the luminaires are in its plane).
    pub ceiling: f64,
    /// On the walls: the downward flux that misses the floor.
    pub walls: f64,
    /// On the floor.
    pub floor: f64,
}

/// Gauss-Legendre nodes and weights on [-1, 1], 8 points: each spacing
/// cell of offsets is integrated by the 8 x 8 product rule.
fn rule8() -> &'static [(f64, f64)] {
    static RULE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    RULE.get_or_init(|| {
        let n = std::num::NonZeroUsize::new(8).expect("non-zero");
        gauss_quad::legendre::GaussLegendre::new(n)
            .as_node_weight_pairs()
            .to_vec()
    })
}

/// A luminaire's upward and downward flux \[lm\]: `int I dw` over each
/// hemisphere by the midpoint rule in `gamma` (0.05 degree) and `C` (0.25
/// degree), which the bilinear photometric table meets to about 1e-6.
pub fn hemisphere_fluxes(lum: &dyn TableLuminaire) -> (f64, f64) {
    let (ng, nc) = (3600, 1440);
    let (dg, dc) = (PI / ng as f64, 2.0 * PI / nc as f64);
    let (mut down, mut up) = (CompensatedSum::default(), CompensatedSum::default());
    for a in 0..ng {
        let g = (a as f64 + 0.5) * dg;
        let (sg, cg) = g.sin_cos();
        let mut ring = 0.0;
        for b in 0..nc {
            let (sc, cc) = ((b as f64 + 0.5) * dc).sin_cos();
            ring += lum.intensity(DVec3::new(sg * cc, sg * sc, -cg));
        }
        let part = ring * sg * dg * dc;
        if a < ng / 2 {
            down.add(part);
        } else {
            up.add(part);
        }
    }
    (up.total(), down.total())
}

impl StandardRoom {
    /// Luminaires along and across the line of sight.
    fn counts(&self) -> (usize, usize) {
        let n = |d: f64| ((d / self.spacing).round() as usize).max(1);
        (n(self.along), n(self.across))
    }

    /// Luminaire positions \[m\]: `x` along the line of sight from the
    /// observer's wall, `y` across from the side wall, `z` the ceiling
    /// plane `eye + h` above the floor.
    pub fn luminaires(&self) -> Vec<DVec3> {
        let (na, nc) = self.counts();
        let z = self.eye + self.h;
        let mut v = Vec::with_capacity(na * nc);
        for i in 0..na {
            for j in 0..nc {
                v.push(DVec3::new(
                    (i as f64 + 0.5) * self.along / na as f64,
                    (j as f64 + 0.5) * self.across / nc as f64,
                    z,
                ));
            }
        }
        v
    }

    /// The eye \[m\]: the middle of the wall `x = 0`.
    pub fn eye_position(&self) -> DVec3 {
        DVec3::new(0.0, 0.5 * self.across, self.eye)
    }

    /// `sum L^2 omega / p^2` [(cd/m^2)^2 sr] over every luminaire of the
    /// room that shows the eye a luminous area, within the field of the
    /// position index ([`in_position_field`]).
    pub fn glare_sum(&self, lum: &dyn TableLuminaire) -> f64 {
        let eye = self.eye_position();
        let mut sum = CompensatedSum::default();
        for c in self.luminaires() {
            let v = c - eye;
            if !in_position_field(v.x, v.y, v.z) {
                continue;
            }
            let d = v.length();
            let w = -v / d;
            let (i, a_p) = (lum.intensity(w), lum.projected_area(w));
            if i > 0.0 && a_p > 0.0 {
                let l = i / a_p;
                let p = position_index(v.x, v.y, v.z);
                sum.add(l * l * (a_p / (d * d)) / (p * p));
            }
        }
        sum.total()
    }

    /// The direct flux on ceiling, walls and floor, given the luminaire's
    /// upward and downward flux ([`hemisphere_fluxes`]). The floor's is
    /// `sum_luminaires int_floor I(r) h_c / |r|^3 dA` (`r` from the
    /// luminaire to the floor point, `h_c = eye + h`), computed as one
    /// integral over the offset `r`: the number of luminaire-floor pairs
    /// with horizontal offset in the spacing cell `(k, l)` is
    /// `(n_along - |k|) (n_across - |l|)` (the cells are centred on whole
    /// multiples of the spacing), each cell by an 8 x 8 Gauss-Legendre rule.
    pub fn direct_flux(&self, lum: &dyn TableLuminaire, (up, down): (f64, f64)) -> DirectFlux {
        let (na, nc) = self.counts();
        let (sa, sc) = (self.along / na as f64, self.across / nc as f64);
        let hc = self.eye + self.h;
        let rule = rule8();
        let mut floor = CompensatedSum::default();
        for k in 1 - na as i64..na as i64 {
            let wk = (na as i64 - k.abs()) as f64;
            for l in 1 - nc as i64..nc as i64 {
                let wl = (nc as i64 - l.abs()) as f64;
                let mut cell = 0.0;
                for &(xa, wa) in rule {
                    let ux = (k as f64 + 0.5 * xa) * sa;
                    for &(xc, wc) in rule {
                        let uy = (l as f64 + 0.5 * xc) * sc;
                        let r = DVec3::new(ux, uy, -hc);
                        let d = r.length();
                        cell += wa * wc * lum.intensity(r / d) * hc / (d * d * d);
                    }
                }
                floor.add(wk * wl * cell * 0.25 * sa * sc);
            }
        }
        let n = (na * nc) as f64;
        let floor = floor.total();
        DirectFlux {
            ceiling: n * up,
            walls: (n * down - floor).max(0.0),
            floor,
        }
    }

    /// The walls' average indirect illuminance \[lx\] from the direct flux:
    /// the three surfaces, each of uniform illuminance, exchange light by
    /// the box's exact view factors, `E_k = E0_k + sum_j F_kj rho_j E_j`.
    pub fn wall_indirect(&self, flux: &DirectFlux) -> f64 {
        let hc = self.eye + self.h;
        let (ac, af) = (self.along * self.across, self.along * self.across);
        let aw = 2.0 * (self.along + self.across) * hc;
        let f_cf = view_factor_parallel(self.along, self.across, hc);
        let f_cw = 1.0 - f_cf;
        let f_wc = ac * f_cw / aw;
        let f_ww = 1.0 - 2.0 * f_wc;
        let f = [[0.0, f_cw, f_cf], [f_wc, f_ww, f_wc], [f_cf, f_cw, 0.0]];
        let e0 = [flux.ceiling / ac, flux.walls / aw, flux.floor / af];
        // Solve (I - F diag(rho)) E = E0 by Gaussian elimination (3 x 3).
        let mut m = [[0.0; 4]; 3];
        for k in 0..3 {
            for j in 0..3 {
                m[k][j] = f64::from(u8::from(k == j)) - f[k][j] * self.rho[j];
            }
            m[k][3] = e0[k];
        }
        for p in 0..3 {
            for k in p + 1..3 {
                let q = m[k][p] / m[p][p];
                let pivot = m[p];
                for (x, y) in m[k].iter_mut().zip(pivot).skip(p) {
                    *x -= q * y;
                }
            }
        }
        let mut e = [0.0; 3];
        for k in (0..3).rev() {
            let s: f64 = (k + 1..3).map(|j| m[k][j] * e[j]).sum();
            e[k] = (m[k][3] - s) / m[k][k];
        }
        e[1] - e0[1]
    }

    /// The tabular rating of the room with luminaire `lum`.
    pub fn rating(&self, lum: &dyn TableLuminaire) -> Tabular {
        let sum = self.glare_sum(lum);
        let flux = self.direct_flux(lum, hemisphere_fluxes(lum));
        let e_wall_ind = self.wall_indirect(&flux);
        Tabular {
            sum,
            e_wall_ind,
            ugr: rating(sum, e_wall_ind),
        }
    }
}

/// [`super::ugr_formula`] over the walls' indirect illuminance; NaN when
/// either is not positive.
fn rating(sum: f64, e_wall_ind: f64) -> f64 {
    if sum > 0.0 && e_wall_ind > 0.0 {
        super::ugr_formula(sum, e_wall_ind)
    } else {
        f64::NAN
    }
}

/// The height `H` \[m\] a table is computed at (any other gives the same
/// ratings to rounding).
pub const TABLE_H: f64 = 2.0;

/// The standard table's rooms, `(X, Y)` in units of `H` (`X` across the
/// line of sight, `Y` along it), in the order the tables print them.
pub const ROOMS: [(f64, f64); 19] = [
    (2.0, 2.0),
    (2.0, 3.0),
    (2.0, 4.0),
    (2.0, 6.0),
    (2.0, 8.0),
    (2.0, 12.0),
    (4.0, 2.0),
    (4.0, 3.0),
    (4.0, 4.0),
    (4.0, 6.0),
    (4.0, 8.0),
    (4.0, 12.0),
    (8.0, 4.0),
    (8.0, 6.0),
    (8.0, 8.0),
    (8.0, 12.0),
    (12.0, 4.0),
    (12.0, 6.0),
    (12.0, 8.0),
];

/// The standard table's reflectances (ceiling, walls, floor).
pub const REFLECTANCES: [[f64; 3]; 5] = [
    [0.7, 0.5, 0.2],
    [0.7, 0.3, 0.2],
    [0.5, 0.5, 0.2],
    [0.5, 0.3, 0.2],
    [0.3, 0.3, 0.2],
];

/// One room of a UGR table: the ratings for each of [`REFLECTANCES`],
/// viewed crosswise and endwise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UgrRow {
    /// Room dimension across the line of sight, in units of `H`.
    pub x: f64,
    /// Room dimension along the line of sight, in units of `H`.
    pub y: f64,
    /// Ratings viewed crosswise.
    pub crosswise: [f64; 5],
    /// Ratings viewed endwise.
    pub endwise: [f64; 5],
}

/// A luminaire's UGR table by the tabular method: [`ROOMS`] by
/// [`REFLECTANCES`], viewed crosswise and endwise, luminaires spaced
/// `spacing_h` times their height `H` above the eye, the floor cavity in
/// the eye plane (module docs). The ratings do not depend on `H`; they
/// are computed at [`TABLE_H`].
pub fn ugr_table(dist: &Goniometric, area: &LuminousArea, spacing_h: f64) -> Vec<UgrRow> {
    use rayon::prelude::*;
    let fluxes = luminaire_fluxes(dist, area);
    ROOMS
        .par_iter()
        .map(|&(x, y)| {
            let [crosswise, endwise] = room_ratings(dist, area, fluxes, (x, y), spacing_h);
            UgrRow {
                x,
                y,
                crosswise,
                endwise,
            }
        })
        .collect()
}

/// The reference ratings a luminaire is labelled with: the standard room
/// `X = 4H`, `Y = 8H`, reflectances 0.7 / 0.5 / 0.2, spacing 0.25 H,
/// `(crosswise, endwise)` (the entries of [`ugr_table`]'s row `4H 8H`).
pub fn reference_ugr(dist: &Goniometric, area: &LuminousArea) -> (f64, f64) {
    let [c, e] = room_ratings(dist, area, luminaire_fluxes(dist, area), (4.0, 8.0), 0.25);
    (c[0], e[0])
}

/// A file luminaire's upward and downward flux \[lm\] ([`hemisphere_fluxes`]).
fn luminaire_fluxes(dist: &Goniometric, area: &LuminousArea) -> (f64, f64) {
    hemisphere_fluxes(&FileLuminaire {
        dist,
        area,
        frame: View::Endwise.frame(),
    })
}

/// The ratings of one standard room `(X, Y)` \[H\], for each of
/// [`REFLECTANCES`], viewed crosswise and endwise.
fn room_ratings(
    dist: &Goniometric,
    area: &LuminousArea,
    fluxes: (f64, f64),
    (x, y): (f64, f64),
    spacing_h: f64,
) -> [[f64; 5]; 2] {
    let h = TABLE_H;
    let mut ratings = [[0.0; 5]; 2];
    for (view, out) in [View::Crosswise, View::Endwise]
        .into_iter()
        .zip(&mut ratings)
    {
        let lum = FileLuminaire {
            dist,
            area,
            frame: view.frame(),
        };
        let room = StandardRoom {
            across: x * h,
            along: y * h,
            eye: 0.0,
            h,
            spacing: spacing_h * h,
            rho: [0.0; 3],
        };
        let sum = room.glare_sum(&lum);
        let flux = room.direct_flux(&lum, fluxes);
        for (rho, r) in REFLECTANCES.iter().zip(out.iter_mut()) {
            *r = rating(sum, StandardRoom { rho: *rho, ..room }.wall_indirect(&flux));
        }
    }
    ratings
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two facing unit squares one unit apart: 0.19982 (Howell C-11); the
    /// limits of a far and a near pair.
    #[test]
    fn parallel_view_factor() {
        assert!((view_factor_parallel(1.0, 1.0, 1.0) - 0.199_825).abs() < 1e-5);
        // Far apart: a b / (pi c^2).
        let far = view_factor_parallel(1.0, 1.0, 1e3);
        assert!((far * PI * 1e6 - 1.0).abs() < 1e-3, "{far}");
        assert!((view_factor_parallel(1e3, 1e3, 1.0) - 1.0).abs() < 3e-3);
    }

    /// An analytic luminaire: `down mu (1 + c2 cos 2C)` below (`mu` the
    /// cosine from the nadir, `C` from `+x`), `up` \[cd\] everywhere above,
    /// a square opening of side `side` \[m\] facing down.
    struct Analytic {
        down: f64,
        up: f64,
        c2: f64,
        side: f64,
    }

    impl TableLuminaire for Analytic {
        fn intensity(&self, w: DVec3) -> f64 {
            let mu = -w.z;
            if mu > 0.0 {
                let c = w.y.atan2(w.x);
                self.down * mu * (1.0 + self.c2 * (2.0 * c).cos())
            } else {
                self.up
            }
        }
        fn projected_area(&self, w: DVec3) -> f64 {
            self.side * self.side * (-w.z).max(0.0)
        }
    }

    const LUM: Analytic = Analytic {
        down: 200.0,
        up: 30.0,
        c2: 0.5,
        side: 0.3,
    };

    /// The hemispheres' flux against the closed forms `pi down` and
    /// `2 pi up` (the `cos 2C` term integrates to 0).
    #[test]
    fn hemisphere_fluxes_closed_form() {
        let (up, down) = hemisphere_fluxes(&LUM);
        assert!((down / (PI * 200.0) - 1.0).abs() < 1e-6, "{down}");
        assert!((up / (2.0 * PI * 30.0) - 1.0).abs() < 1e-6, "{up}");
    }

    /// The floor's direct flux by the offset-cell integral against a brute
    /// force sum over luminaires of a midpoint rule over the floor (a code
    /// path that shares nothing but the luminaire); and the three parts add
    /// up to the luminaires' flux.
    #[test]
    fn floor_flux_against_brute_force() {
        let room = StandardRoom {
            across: 3.0,
            along: 2.0,
            eye: 1.0,
            h: 1.5,
            spacing: 1.0,
            rho: [0.0; 3],
        };
        let fluxes = hemisphere_fluxes(&LUM);
        let f = room.direct_flux(&LUM, fluxes);
        let hc = room.eye + room.h;
        let (nx, ny) = (600, 900);
        let (dx, dy) = (room.along / nx as f64, room.across / ny as f64);
        let mut brute = CompensatedSum::default();
        for c in room.luminaires() {
            assert_eq!(c.z, hc);
            for u in 0..nx {
                for v in 0..ny {
                    let p = DVec3::new((u as f64 + 0.5) * dx, (v as f64 + 0.5) * dy, 0.0);
                    let r = p - c;
                    let d = r.length();
                    brute.add(LUM.intensity(r / d) * hc / (d * d * d) * dx * dy);
                }
            }
        }
        let brute = brute.total();
        assert!(
            (f.floor / brute - 1.0).abs() < 2e-5,
            "{} vs {brute}",
            f.floor
        );
        assert_eq!(room.luminaires().len(), 6);
        let total = 6.0 * (fluxes.0 + fluxes.1);
        assert!(((f.floor + f.walls + f.ceiling) / total - 1.0).abs() < 1e-12);
        assert!(f.walls > 0.1 * f.floor && f.ceiling == 6.0 * fluxes.0);
    }

    /// Flux balance of the three-surface model: black surfaces give no
    /// indirect light; the walls' indirect illuminance grows with each
    /// reflectance; a white box with no absorption has no finite answer
    /// (the solve divides by zero) and is not a standard room.
    #[test]
    fn background_limits() {
        let room = StandardRoom {
            across: 8.0,
            along: 8.0,
            eye: 1.2,
            h: 2.0,
            spacing: 0.5,
            rho: [0.0, 0.0, 0.0],
        };
        let flux = room.direct_flux(&LUM, hemisphere_fluxes(&LUM));
        assert_eq!(room.wall_indirect(&flux), 0.0);
        let e = |rho| StandardRoom { rho, ..room }.wall_indirect(&flux);
        let base = e([0.7, 0.5, 0.2]);
        assert!(base > 0.0);
        assert!(e([0.8, 0.5, 0.2]) > base && e([0.7, 0.6, 0.2]) > base);
        assert!(e([0.7, 0.5, 0.3]) > base);
        // Only the floor reflects: its first bounce reaches the walls by
        // F_fw, nothing returns to the floor.
        let hc = 3.2;
        let f_cf = view_factor_parallel(8.0, 8.0, hc);
        let aw = 2.0 * 16.0 * hc;
        let want = 0.2 * flux.floor / 64.0 * 64.0 * (1.0 - f_cf) / aw;
        assert!((e([0.0, 0.0, 0.2]) / want - 1.0).abs() < 1e-12);
    }

    /// The room's axes: `along` runs along the line of sight from the
    /// observer's wall, `across` to the side. A room one luminaire wide and
    /// seven deep puts all seven straight ahead of the eye, so the sum is
    /// the hand-written one (position index at `tau = 0`, `C = 180` deg from
    /// the luminaire to the eye) over the five beyond the brows' cut-off
    /// (CIE 117's table has no index at `T = 0` from `H/R = 1.8` on: the
    /// first two, at `H/R = 8` and `2.67`, do not count); with the axes
    /// swapped they would stand to the side.
    #[test]
    fn room_axes_by_hand() {
        let room = StandardRoom {
            across: 0.5,
            along: 3.5,
            eye: 1.2,
            h: 2.0,
            spacing: 0.5,
            rho: [0.0; 3],
        };
        let mut want = 0.0;
        for x in [1.25f64, 1.75, 2.25, 2.75, 3.25] {
            let d2 = x * x + 4.0;
            let mu = 2.0 / d2.sqrt();
            let i = 200.0 * mu * 1.5;
            let p = super::super::guth_index(0.0, (2.0 / x).atan().to_degrees());
            want += i * i / (0.09 * mu * d2 * p * p);
        }
        let got = room.glare_sum(&LUM);
        assert!((got / want - 1.0).abs() < 1e-12, "{got} vs {want}");
    }

    /// The fraction of the light leaving the walls (uniform, diffuse) that
    /// reaches the ceiling, by stratified ray casting from both kinds of
    /// wall: code that shares nothing with the view-factor algebra.
    fn walls_to_ceiling(along: f64, across: f64, hc: f64) -> f64 {
        let n = 64;
        let mut hit = [0.0; 2];
        // Wall 0 at x = 0 (width `across`), wall 1 at y = 0 (width `along`).
        for (wall, (width, depth)) in [(across, along), (along, across)].into_iter().enumerate() {
            let mut count = 0usize;
            for a in 0..n {
                for b in 0..n {
                    let (t, z) = (
                        (a as f64 + 0.5) / n as f64 * width,
                        (b as f64 + 0.5) / n as f64 * hc,
                    );
                    for c in 0..n {
                        for e in 0..n {
                            let (u1, u2) =
                                ((c as f64 + 0.5) / n as f64, (e as f64 + 0.5) / n as f64);
                            // Cosine-weighted about the wall's normal.
                            let (r, phi) = (u1.sqrt(), 2.0 * PI * u2);
                            let (dn, dt, dz) = ((1.0 - u1).sqrt(), r * phi.cos(), r * phi.sin());
                            if dz <= 0.0 {
                                continue;
                            }
                            let s = (hc - z) / dz;
                            let (pn, pt) = (dn * s, t + dt * s);
                            if pn <= depth && (0.0..=width).contains(&pt) {
                                count += 1;
                            }
                        }
                    }
                }
            }
            hit[wall] = count as f64 / (n as f64).powi(4);
        }
        (hit[0] * across + hit[1] * along) / (across + along)
    }

    /// The walls' exchange: only the ceiling reflects, `E_W = F_wc rho_c
    /// E0_c`; only the walls, `E_W = E0_w F_ww rho / (1 - F_ww rho)` with
    /// `F_ww = 1 - 2 F_wc`; `F_wc` by ray casting (stratified, 64^4 rays:
    /// 4.5e-4 above the exact 0.28369 here, converging as the grid is
    /// refined; the bounds 2e-3 relative).
    #[test]
    fn wall_exchange_against_ray_casting() {
        let room = StandardRoom {
            across: 4.0,
            along: 12.0,
            eye: 1.2,
            h: 2.0,
            spacing: 0.5,
            rho: [0.0; 3],
        };
        let hc = 3.2;
        let f_wc = walls_to_ceiling(room.along, room.across, hc);
        let aw = 2.0 * (room.along + room.across) * hc;
        let flux = DirectFlux {
            ceiling: 1000.0,
            walls: 2000.0,
            floor: 3000.0,
        };
        let e = |rho| StandardRoom { rho, ..room }.wall_indirect(&flux);
        let want = f_wc * 0.7 * 1000.0 / (room.along * room.across);
        assert!(
            (e([0.7, 0.0, 0.0]) / want - 1.0).abs() < 2e-3,
            "{} vs {want}",
            e([0.7, 0.0, 0.0])
        );
        let f_ww = 1.0 - 2.0 * f_wc;
        let want = 2000.0 / aw * f_ww * 0.5 / (1.0 - f_ww * 0.5);
        assert!(
            (e([0.0, 0.5, 0.0]) / want - 1.0).abs() < 2e-3,
            "{} vs {want}",
            e([0.0, 0.5, 0.0])
        );
    }

    fn file(name: &str) -> (Goniometric, LuminousArea) {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("data/photometry")
            .join(name);
        let p = crate::io::photometry::read(&path).unwrap();
        let area = LuminousArea::of_file(&p.opening).unwrap();
        (Goniometric::new(&p, 1.0), area)
    }

    /// A rotationally symmetric luminaire with a flat opening rates the
    /// same crosswise and endwise; one with a narrow C90 beam does not;
    /// twice the flux adds `8 log10 2` to every entry (sum `~ Phi^2`,
    /// background `~ Phi`); more luminaires in view rate higher.
    #[test]
    fn table_properties() {
        let (g, a) = file("lm63_2002.ies");
        let t = ugr_table(&g, &a, 0.25);
        assert_eq!(t.len(), 19);
        for r in &t {
            for k in 0..5 {
                assert!(r.crosswise[k].is_finite());
                assert!((r.crosswise[k] - r.endwise[k]).abs() < 1e-9, "{r:?}");
            }
            // Darker walls and ceiling: less background, more glare.
            assert!(r.crosswise[1] > r.crosswise[0] && r.crosswise[4] > r.crosswise[3]);
        }
        // 2H x 2H against 2H x 12H (looking along a long room): higher.
        assert!(t[5].crosswise[0] > t[0].crosswise[0] + 1.0);
        let p = crate::io::photometry::read(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/photometry/lm63_2002.ies"),
        )
        .unwrap();
        let t2 = ugr_table(&Goniometric::new(&p, 2.0), &a, 0.25);
        for (r, r2) in t.iter().zip(&t2) {
            for k in 0..5 {
                let d = r2.endwise[k] - r.endwise[k];
                assert!((d - 8.0 * 2f64.log10()).abs() < 1e-9, "{d}");
            }
        }
        let (g, a) = file("sym_quadrant.ies");
        let t = ugr_table(&g, &a, 0.25);
        // The row `X = 2H, Y = 12H` is the room 2H across, 12H along the
        // line of sight, not its transpose (which rates far apart).
        assert_eq!((t[5].x, t[5].y), (2.0, 12.0));
        for (view, got) in [
            (View::Crosswise, t[5].crosswise),
            (View::Endwise, t[5].endwise),
        ] {
            let lum = FileLuminaire {
                dist: &g,
                area: &a,
                frame: view.frame(),
            };
            let room = |across, along| StandardRoom {
                across,
                along,
                eye: 0.0,
                h: 2.0,
                spacing: 0.5,
                rho: REFLECTANCES[0],
            };
            let want = room(4.0, 24.0).rating(&lum).ugr;
            assert!(
                (got[0] - want).abs() < 1e-6,
                "{view:?}: {} vs {want}",
                got[0]
            );
            // The ratings depend on the room only in units of H: the same
            // room at H = 5 m; but a real floor 1.2 m below the eye (at H =
            // 2 m) changes them.
            let scaled = StandardRoom {
                across: 10.0,
                along: 60.0,
                h: 5.0,
                spacing: 1.25,
                ..room(0.0, 0.0)
            };
            let at_5 = scaled.rating(&lum).ugr;
            assert!((at_5 - want).abs() < 1e-9, "{view:?}: {at_5} vs {want}");
            let seated = StandardRoom {
                eye: 1.2,
                ..room(4.0, 24.0)
            };
            let real_floor = seated.rating(&lum).ugr;
            assert!((real_floor - want).abs() > 0.05, "{view:?}: {real_floor}");
            let transposed = room(24.0, 4.0).rating(&lum).ugr;
            assert!(
                (want - transposed).abs() > 0.5,
                "{view:?}: {want} vs {transposed}"
            );
        }
        let most = t
            .iter()
            .map(|r| (r.crosswise[0] - r.endwise[0]).abs())
            // NaN-propagating: a NaN entry fails rather than drops out.
            .fold(0.0, |m: f64, d| if d.is_nan() || d > m { d } else { m });
        assert!(most > 0.5, "{most}");
    }
}
