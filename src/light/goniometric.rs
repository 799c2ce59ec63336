//! The intensity distribution of a goniometric luminaire (from an IES or
//! EULUMDAT file, [`crate::io::photometry`]): interpolation, power and
//! emission sampling, in the luminaire's own frame.
//!
//! # Frame and angles
//!
//! Type C (every EULUMDAT file, most IES files): the photometric nadir
//! (`gamma = 0`) points along `-z`, the C0 plane contains `+x` and C90
//! contains `+y`; a unit direction `d` has `gamma = acos(-d_z)` and
//! `C = atan2(d_y, d_x)` in `[0, 360)`. At the poles (`gamma` 0 or 180),
//! where the azimuth is undefined and the C-planes of a measured table may
//! still differ, a direction's intensity is their mean (within 1e-12 rad of
//! the pole, so that rounding in a turned frame does not pick a plane): the bilinear
//! interpolant averaged over C (each plane weighted by the span of C it
//! interpolates; the plain mean of equally spaced planes), zero where the
//! pole lies outside the measured range; [`Goniometric::intensity_at`],
//! given an azimuth, keeps that plane's value. Type B (floodlights, the
//! B-beta system): the beam axis is `-z` and the B-planes turn about the
//! transverse axis `y`. The file's vertical angle `V` is the B-plane's
//! angle (a floodlight aimed level tilts its B-planes up and down about its
//! horizontal trunnion axis), from the beam axis towards `+x`; the
//! horizontal angle `H` is the lateral angle beta within the plane, out of
//! the `xz` plane towards `+y`: `d = (cos H sin V, sin H, -cos H cos V)`.
//! Which angle is which follows LM-63 and Radiance's `ies2rad` (the file's
//! horizontal angles go to `srcB_horiz`, an arcsine of the lateral
//! component; a laterally symmetric floodlight lists `H` from 0 to 90); the
//! signs follow the type C frame here, as the usual B-to-C conversion
//! `tan V = cos C tan gamma`, `sin H = sin C sin gamma` gives them (Radiance's
//! own frame is mirrored, its type B too). Internally a type B table is
//! transposed: its rows (the "horizontal" angles of the code below) are
//! the planes `V`, its columns (the "vertical" ones, with the measure
//! `cos beta d beta`) the laterals `H`. Type A (the A-alpha system) turns
//! its planes about the other transverse axis, `x`, a floodlight aimed
//! level's vertical one: there the plane's angle is the horizontal angle
//! `H`, from the beam towards `+y`, and `V` the angle out of the plane
//! towards `+x`, `d = (sin V, cos V sin H, -cos V cos H)` (the names hold:
//! `H` horizontal, `V` vertical, as Blender's reader takes type A); its
//! table is not transposed.
//!
//! # Interpolation
//!
//! Bilinear in (horizontal angle, vertical angle), the de-facto rule of
//! photometric software, after expanding the stored planes by the file's
//! symmetry to a full turn (type C) or `H` to `[-90, 90]` (types A, B),
//! periodic in `C`. **Zero outside the measured range** of `gamma` (type
//! C) or `V` (types A, B): a downlight measured over 0-90
//! degrees emits nothing upward (extrapolating the last value would add
//! flux the file does not have).
//!
//! # Power and sampling
//!
//! `power = int I dOmega` \[lm\] is integrated exactly for the bilinear
//! interpolant, cell by cell (`dOmega = cos H dH dV` for type B, `cos V dV dH` for A,
//! `sin gamma dgamma dC` for type C). Emission directions are drawn from a
//! piecewise-constant density: a cell is picked in proportion to its
//! largest corner intensity times its solid angle (an alias-free binary
//! search over the cumulative table, `O(log n)`), and a direction uniformly
//! in solid angle within it. The density is positive wherever the
//! interpolant is, so the weight `I(d) / pdf(d)` is exact and unbiased.

use super::angle_grid::{AngleGrid, AngleKind};
use crate::io::photometry::{PhotometricType, Photometry, Symmetry};
use glam::DVec3;
use std::f64::consts::PI;

/// A type C direction whose polar sine (its distance from the nadir axis
/// over its length) is at most this is at a pole: 1e-12 rad, well above the
/// rounding left in the local components of a direction along a turned
/// frame's nadir (~1e-16), so that the pole's value does not depend on it.
const POLE_SIN: f64 = 1e-12;

/// A goniometric intensity distribution \[cd\] over the luminaire's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Goniometric {
    kind: PhotometricType,
    /// Row angles \[rad\], ascending: the C-planes over a full turn (type
    /// C), the planes: `V` as measured (type B), `H` over `[-90, 90]` deg
    /// (type A; module docs).
    h: Vec<f64>,
    /// Column angles \[rad\], ascending: `gamma` as measured (type C), the
    /// angle out of the planes: `H` over `[-90, 90]` deg (type B), `V` as
    /// measured (type A).
    v: Vec<f64>,
    /// Intensity \[cd\] at `(h[i], v[k])`: `i[i * v.len() + k]`.
    i: Vec<f64>,
    /// Cumulative sampling weights of the cells `(i, k)`, last entry 1.
    cdf: Vec<f64>,
    /// Total of the sampling weights [cd sr].
    weight_total: f64,
    /// Emitted flux \[lm\].
    power: f64,
    /// Every horizontal plane holds the same intensities (rotational
    /// symmetry of a type C table): the intensity depends on gamma alone,
    /// and no azimuth is computed.
    rotational: bool,
    /// Type C: the vertical and horizontal angles located from a
    /// direction's components without `acos`/`atan2` ([`AngleGrid`]).
    grids: Option<(AngleGrid, Option<AngleGrid>)>,
    /// Type C with `grids`: the bilinear coefficients `[A, C, B, D]` \[cd\]
    /// of the cell `h_a..h_{a+1}`, `v_k..v_{k+1}` at `coef[a * stride +
    /// k]`, `I = (A + B tv) + th (C + D tv)` with `A = I00`, `B = I01 -
    /// I00`, `C = I10 - I00`, `D = (I11 - I10) - (I01 - I00)` (first index
    /// horizontal): one entry per cell (one load) and four products fewer
    /// than the corners. A zero column after each row and a zero row after
    /// the last hold the grids' virtual cells (outside the measured
    /// angles); the grids' offsets sum to the entry.
    coef: Vec<[f64; 4]>,
    /// Entries per row of `coef` (`v.len()`: the cells and the zero one).
    stride: usize,
    /// Type C: the intensity \[cd\] at the poles gamma 0 and gamma 180, the
    /// mean over C of the interpolant there (module docs); 0 where the
    /// pole lies outside the measured range.
    poles: [f64; 2],
    /// The file's luminous opening \[m\] (all zero: the file gives none), for
    /// glare ([`crate::glare`]): luminance and solid angle need its area.
    opening: crate::io::photometry::Opening,
}

/// A direction drawn from [`Goniometric::sample`].
#[derive(Clone, Copy, Debug)]
pub struct GonioSample {
    /// Unit direction in the luminaire's frame.
    pub d: DVec3,
    /// Density per solid angle [1/sr].
    pub pdf: f64,
    /// Intensity towards `d` \[cd\].
    pub i: f64,
}

impl Goniometric {
    /// Expand a photometric table by its symmetry and build the sampler.
    /// `scale` multiplies every intensity (a multiplier or a flux override).
    pub fn new(p: &Photometry, scale: f64) -> Self {
        let (h_deg, v_deg, rows) = expand(p);
        let nv = v_deg.len();
        let h: Vec<f64> = h_deg.iter().map(|a| a.to_radians()).collect();
        let v: Vec<f64> = v_deg.iter().map(|a| a.to_radians()).collect();
        let i: Vec<f64> = rows.iter().flatten().map(|c| c * scale).collect();
        let mut g = Self {
            kind: p.kind,
            h,
            v,
            i,
            cdf: Vec::new(),
            weight_total: 0.0,
            power: 0.0,
            rotational: false,
            grids: None,
            coef: Vec::new(),
            stride: nv,
            poles: [0.0; 2],
            opening: p.opening,
        };
        if p.kind == PhotometricType::C && g.h.len() > 1 && nv > 0 {
            // The trapezoidal rule is exact for the piecewise-linear
            // interpolant in C; the expanded table spans a full turn.
            let span = g.h[g.h.len() - 1] - g.h[0];
            let mean = |k: usize| {
                (0..g.h.len() - 1)
                    .map(|a| (g.h[a + 1] - g.h[a]) * 0.5 * (g.at(a, k) + g.at(a + 1, k)))
                    .sum::<f64>()
                    / span
            };
            let poles = [
                if v_deg[0] == 0.0 { mean(0) } else { 0.0 },
                if v_deg[nv - 1] == 180.0 {
                    mean(nv - 1)
                } else {
                    0.0
                },
            ];
            g.poles = poles;
        }
        g.rotational = p.kind == PhotometricType::C
            && !g.h.is_empty()
            && (0..g.h.len()).all(|a| (0..nv).all(|k| g.at(a, k) == g.at(0, k)));
        // Offsets into `coef`: the polar cell k is column k (virtual: the
        // zero column nv - 1), the azimuth cell a is row a (virtual: the
        // zero row after the last).
        let (stride, nhc) = (g.stride, g.h.len().saturating_sub(1));
        if p.kind == PhotometricType::C
            && let Some(vg) =
                AngleGrid::with_offsets(AngleKind::Polar, &g.v, 1, nv.saturating_sub(1))
        {
            let hg = if g.rotational {
                None
            } else {
                AngleGrid::with_offsets(AngleKind::Azimuth, &g.h, stride, nhc * stride)
            };
            if g.rotational || hg.is_some() {
                g.grids = Some((vg, hg));
                g.coef = vec![[0.0; 4]; (nhc + 1) * stride];
                for a in 0..nhc {
                    for k in 0..nv.saturating_sub(1) {
                        let (i00, i01) = (g.at(a, k), g.at(a, k + 1));
                        let (i10, i11) = (g.at(a + 1, k), g.at(a + 1, k + 1));
                        g.coef[a * stride + k] =
                            [i00, i10 - i00, i01 - i00, (i11 - i10) - (i01 - i00)];
                    }
                }
            }
        }
        let mut acc = 0.0;
        let mut power = 0.0;
        let (nh, nvc) = (g.h.len().saturating_sub(1), nv.saturating_sub(1));
        for a in 0..nh {
            for k in 0..nvc {
                let c = [
                    g.at(a, k),
                    g.at(a, k + 1),
                    g.at(a + 1, k),
                    g.at(a + 1, k + 1),
                ];
                let dh = g.h[a + 1] - g.h[a];
                let omega = dh * g.measure(g.v[k], g.v[k + 1]);
                acc += c.iter().copied().fold(0.0, f64::max) * omega;
                power += dh
                    * g.linear_moment(g.v[k], g.v[k + 1], 0.5 * (c[0] + c[2]), 0.5 * (c[1] + c[3]));
                g.cdf.push(acc);
            }
        }
        if acc > 0.0 {
            for x in &mut g.cdf {
                *x /= acc;
            }
        }
        if let Some(last) = g.cdf.last_mut() {
            *last = 1.0;
        }
        g.weight_total = acc;
        g.power = power;
        g
    }

    fn at(&self, a: usize, k: usize) -> f64 {
        self.i[a * self.v.len() + k]
    }

    /// `int_{v0}^{v1}` of the column measure: `cos v0 - cos v1` for type C
    /// (`sin gamma dgamma`), `sin v1 - sin v0` for types A and B (the cosine
    /// of the angle out of the planes: `cos H dH` for B, `cos V dV` for A).
    fn measure(&self, v0: f64, v1: f64) -> f64 {
        match self.kind {
            PhotometricType::C => v0.cos() - v1.cos(),
            _ => v1.sin() - v0.sin(),
        }
    }

    /// `int_{v0}^{v1} f(v) dmu(v)` for `f` linear from `f0` to `f1`.
    fn linear_moment(&self, v0: f64, v1: f64, f0: f64, f1: f64) -> f64 {
        let dv = v1 - v0;
        // int (v - v0) dmu over [v0, v1].
        let m1 = match self.kind {
            // int (v - v0) sin v dv = [-(v - v0) cos v + sin v]
            PhotometricType::C => -dv * v1.cos() + v1.sin() - v0.sin(),
            // int (v - v0) cos v dv = [(v - v0) sin v + cos v]
            _ => dv * v1.sin() + v1.cos() - v0.cos(),
        };
        f0 * self.measure(v0, v1) + (f1 - f0) / dv * m1
    }

    /// Layout of the angles (type C, B or A).
    pub fn kind(&self) -> PhotometricType {
        self.kind
    }

    /// Emitted flux \[lm\], exact for the bilinear interpolant.
    pub fn power(&self) -> f64 {
        self.power
    }

    /// Largest intensity of the table \[cd\].
    pub fn max_intensity(&self) -> f64 {
        self.i.iter().copied().fold(0.0, f64::max)
    }

    /// Why the table cannot be used, if it cannot: its flux is not finite,
    /// or its largest intensity lies above [`crate::scene::MAX_INTENSITY`]
    /// or is positive but below [`crate::scene::MIN_INTENSITY`] (a
    /// candela multiplier, ballast or conversion factor near 1e308 makes
    /// infinite intensities out of finite numbers).
    pub fn range_error(&self) -> Option<String> {
        use crate::scene::{MAX_INTENSITY, MIN_INTENSITY};
        let m = self.max_intensity();
        let ok = self.power().is_finite() && m <= MAX_INTENSITY && (m == 0.0 || m >= MIN_INTENSITY);
        (!ok).then(|| {
            format!(
                "intensities out of range: the largest must be 0 or between {MIN_INTENSITY:e} and \
                 {MAX_INTENSITY:e} cd"
            )
        })
    }

    /// (row, column) angles \[rad\] of a unit direction in the luminaire's
    /// frame: `(C, gamma)` for type C, `(V, H)` for type B, `(H, V)` for
    /// type A (module docs).
    pub fn angles(&self, d: DVec3) -> (f64, f64) {
        match self.kind {
            PhotometricType::C => {
                let g = (-d.z).clamp(-1.0, 1.0).acos();
                let mut c = d.y.atan2(d.x);
                if c < 0.0 {
                    c += 2.0 * PI;
                }
                (c, g)
            }
            PhotometricType::B => ((d.x).atan2(-d.z), d.y.clamp(-1.0, 1.0).asin()),
            PhotometricType::A => ((d.y).atan2(-d.z), d.x.clamp(-1.0, 1.0).asin()),
        }
    }

    /// The unit direction of (row, column) angles \[rad\] ([`Self::angles`]).
    pub fn direction(&self, h: f64, v: f64) -> DVec3 {
        match self.kind {
            PhotometricType::C => {
                let (sg, cg) = v.sin_cos();
                let (sc, cc) = h.sin_cos();
                DVec3::new(sg * cc, sg * sc, -cg)
            }
            PhotometricType::B => {
                let (sv, cv) = v.sin_cos();
                let (sh, ch) = h.sin_cos();
                DVec3::new(cv * sh, sv, -cv * ch)
            }
            PhotometricType::A => {
                let (sv, cv) = v.sin_cos();
                let (sh, ch) = h.sin_cos();
                DVec3::new(sv, cv * sh, -cv * ch)
            }
        }
    }

    /// The direct term `I(w) c / |w|^3` \[lx\] of a luminaire whose axes are
    /// `frame`, towards a receiver at offset `w` \[m\] from it (not
    /// normalised), where `c = n . (-w)` \[m\] is the receiver normal's
    /// projection (0 for a receiver on the luminaire). A rotationally
    /// symmetric table needs only `|w|` and the distance from the nadir axis.
    #[inline(always)]
    pub fn direct_term(&self, frame: &super::LuminaireFrame, w: DVec3, c: f64) -> f64 {
        if let Some((vg, None)) = &self.grids {
            let wz = w.dot(frame.z);
            let perp = w - frame.z * wz;
            let (len, r) = (w.length(), perp.length());
            if len == 0.0 {
                return 0.0;
            }
            let inv = len.recip();
            return self.along_gamma(vg, -wz * inv, r * inv) * c * (inv * inv * inv);
        }
        if let Some((vg, Some(hg))) = &self.grids {
            // Type C without rotational symmetry: the local components
            // unnormalised; |w| and the axis distance r give the polar
            // (cos, sin) and r alone the azimuth's, so the two searches
            // are independent of each other.
            let (lx, ly, lz) = (w.dot(frame.x), w.dot(frame.y), w.dot(frame.z));
            let r2 = lx * lx + ly * ly;
            let d2 = r2 + lz * lz;
            if d2 == 0.0 {
                return 0.0;
            }
            let (len, r) = (d2.sqrt(), r2.sqrt());
            let inv = len.recip();
            return self.bilinear_c(vg, hg, (-lz * inv, r * inv), (lx, ly, r))
                * c
                * (inv * inv * inv);
        }
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let inv = d2.sqrt().recip();
        self.intensity(frame.to_local(w * inv)) * c * (inv * inv * inv)
    }

    /// The file's luminous opening \[m\] (width, length, height of the
    /// luminous sides; all zero when the file gives none).
    pub fn file_opening(&self) -> crate::io::photometry::Opening {
        self.opening
    }

    /// Intensity \[cd\] towards unit world direction `w` of a luminaire whose
    /// axes are `frame`: [`Self::intensity`] of the local direction. A
    /// rotationally symmetric table needs only the nadir axis: `cos gamma =
    /// -w . z` and `sin gamma = |w - (w . z) z|`.
    #[inline(always)]
    pub fn intensity_world(&self, frame: &super::LuminaireFrame, w: DVec3) -> f64 {
        if let Some((vg, None)) = &self.grids {
            let cz = w.dot(frame.z);
            let r = (w - frame.z * cz).length();
            return self.along_gamma(vg, -cz, r);
        }
        self.intensity(frame.to_local(w))
    }

    /// Intensity \[cd\] towards unit direction `d` (luminaire frame): the
    /// bilinear rule of [`Self::intensity_at`], with type C cells found
    /// without inverse trigonometry ([`AngleGrid`]).
    #[inline(always)]
    pub fn intensity(&self, d: DVec3) -> f64 {
        let Some((vg, hg)) = &self.grids else {
            if self.kind == PhotometricType::C && d.x.hypot(d.y) <= POLE_SIN * d.length() {
                // A pole: the planes' mean (index 1 straight up).
                return self.poles[usize::from(d.z > 0.0)];
            }
            let (h, v) = self.angles(d);
            return self.intensity_at(h, v);
        };
        // sin gamma from the transverse components: accurate at the poles,
        // where sqrt(1 - cos^2) loses half the digits.
        let (c, r) = (-d.z, (d.x * d.x + d.y * d.y).sqrt());
        match hg {
            // Rotational symmetry: gamma alone, no azimuth.
            None => self.along_gamma(vg, c, r),
            Some(hg) => self.bilinear_c(vg, hg, (c, r), (d.x, d.y, r)),
        }
    }

    /// The linear rule of a rotationally symmetric type C table in its
    /// polar grid, from the polar angle's `(cos, sin)`: zero outside the
    /// measured angles (a virtual cell's zero columns).
    #[inline(always)]
    fn along_gamma(&self, vg: &AngleGrid, c: f64, s: f64) -> f64 {
        let (j, t) = vg.locate_cell(true, c, s);
        // (Rotational: C = D = 0. t may leave [0, 1] by an ulp at a node:
        // no negative intensity.)
        let [a, _, b, _] = self.coef[j];
        (a + t * b).max(0.0)
    }

    /// The bilinear rule of a type C table in its angle grids, from the
    /// polar angle's `(cos, sin)` and the azimuth's components `(x, y)`
    /// with `r = hypot(x, y)` (any common scale): zero outside the
    /// measured angles (the grids' virtual cells point at zero entries).
    /// At the poles (`s <= POLE_SIN`), where there is no azimuth, the
    /// planes' mean (module docs).
    #[inline(always)]
    fn bilinear_c(
        &self,
        vg: &AngleGrid,
        hg: &AngleGrid,
        (c, s): (f64, f64),
        (x, y, r): (f64, f64, f64),
    ) -> f64 {
        if s <= POLE_SIN {
            // (c > 0: gamma 0, the nadir; c < 0: gamma 180.)
            return self.poles[usize::from(c < 0.0)];
        }
        let (jv, tv) = vg.locate_cell(true, c, s);
        let inv = r.recip();
        let (cc, sc) = (x * inv, y * inv);
        let (jh, th) = hg.locate_cell(false, cc, sc);
        let j = jh + jv;
        // (intensity_at's lo and hi - lo, to rounding, at once.)
        let [a, c, b, d] = self.coef[j];
        let (lo, slope) = (a + tv * b, c + tv * d);
        // (tv, th may leave [0, 1] by an ulp at a node: no negative
        // intensity.)
        (lo + th * slope).max(0.0)
    }

    /// Intensity \[cd\] at (row, column) angles `(h, v)` \[rad\]
    /// ([`Self::angles`]): bilinear, zero outside the measured range.
    /// At a pole this is plane `h`'s own value, not the planes' mean that
    /// [`Self::intensity`] gives a direction there.
    pub fn intensity_at(&self, h: f64, v: f64) -> f64 {
        let (nh, nv) = (self.h.len(), self.v.len());
        if nv == 0
            || nh == 0
            || v < self.v[0]
            || v > self.v[nv - 1]
            || h < self.h[0]
            || h > self.h[nh - 1]
        {
            return 0.0;
        }
        let (a, th) = locate(&self.h, h);
        let (k, tv) = locate(&self.v, v);
        let a1 = (a + 1).min(nh - 1);
        let k1 = (k + 1).min(nv - 1);
        let lo = self.at(a, k) + tv * (self.at(a, k1) - self.at(a, k));
        let hi = self.at(a1, k) + tv * (self.at(a1, k1) - self.at(a1, k));
        lo + th * (hi - lo)
    }

    /// Number of cells of the emission sampler's table (searched by bisection).
    pub fn cells(&self) -> usize {
        self.cdf.len()
    }

    /// Draw a direction: `u[0]` picks the cell, `u[1]` places the
    /// direction across it in the horizontal angle and the separate uniform
    /// `u2` in the vertical one (uniformly in solid angle within the cell;
    /// module docs). `None` when the table is all zero.
    pub fn sample(&self, u: [f64; 2], u2: f64) -> Option<GonioSample> {
        if self.weight_total <= 0.0 {
            return None;
        }
        let cell = self
            .cdf
            .partition_point(|&c| c <= u[0])
            .min(self.cdf.len() - 1);
        let nvc = self.v.len() - 1;
        let (a, k) = (cell / nvc, cell % nvc);
        let h = self.h[a] + u[1] * (self.h[a + 1] - self.h[a]);
        let (v0, v1) = (self.v[k], self.v[k + 1]);
        let v = match self.kind {
            // Uniform in cos gamma between the cell's edges.
            PhotometricType::C => {
                let c = v0.cos() + u2 * (v1.cos() - v0.cos());
                c.clamp(-1.0, 1.0).acos()
            }
            // Uniform in sin V.
            _ => {
                let s = v0.sin() + u2 * (v1.sin() - v0.sin());
                s.clamp(-1.0, 1.0).asin()
            }
        };
        let d = self.direction(h, v);
        let pdf = self.pdf_cell(a, k);
        Some(GonioSample {
            d,
            pdf,
            i: self.intensity_at(h, v),
        })
    }

    /// Density [1/sr] of [`Self::sample`] towards unit direction `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        let (h, v) = self.angles(d);
        let (nh, nv) = (self.h.len(), self.v.len());
        if self.weight_total <= 0.0
            || v < self.v[0]
            || v > self.v[nv - 1]
            || h < self.h[0]
            || h > self.h[nh - 1]
        {
            return 0.0;
        }
        let (a, _) = locate(&self.h, h);
        let (k, _) = locate(&self.v, v);
        self.pdf_cell(a.min(nh - 2), k.min(nv - 2))
    }

    fn pdf_cell(&self, a: usize, k: usize) -> f64 {
        let nvc = self.v.len() - 1;
        let cell = a * nvc + k;
        let p = self.cdf[cell] - if cell > 0 { self.cdf[cell - 1] } else { 0.0 };
        let omega = (self.h[a + 1] - self.h[a]) * self.measure(self.v[k], self.v[k + 1]);
        if omega > 0.0 { p / omega } else { 0.0 }
    }
}

/// Index `k` with `xs[k] <= x <= xs[k + 1]` and the fraction of the way.
fn locate(xs: &[f64], x: f64) -> (usize, f64) {
    let n = xs.len();
    if n < 2 {
        return (0, 0.0);
    }
    let k = xs.partition_point(|&a| a <= x).clamp(1, n - 1) - 1;
    let span = xs[k + 1] - xs[k];
    let t = if span > 0.0 {
        ((x - xs[k]) / span).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (k, t)
}

/// The table in the layout of [`Goniometric`]: its row angles, column
/// angles \[deg\] and one row per row angle. Type C: the C-planes over a
/// full turn `[0, 360]` (periodic) by the file's symmetry, by `gamma`.
/// Type B: transposed, the planes `V` as stored by the laterals `H`
/// expanded to `[-90, 90]`. Type A: the planes `H` expanded to `[-90, 90]`
/// by `V`. In both a file from `H = 0` is symmetric in `H`; one `H`, the
/// same at every `H`.
fn expand(p: &Photometry) -> (Vec<f64>, Vec<f64>, Vec<Vec<f64>>) {
    if p.kind == PhotometricType::B {
        let mut lat: Vec<(f64, usize)> = p.h_angles.iter().copied().zip(0..).collect();
        if lat.len() == 1 {
            lat = vec![(-90.0, 0), (90.0, 0)];
        } else if lat.first().is_some_and(|&(a, _)| a >= 0.0) {
            let mirrored: Vec<(f64, usize)> = lat.iter().map(|&(a, i)| (-a, i)).collect();
            lat.extend(mirrored);
        }
        lat.sort_by(|a, b| a.0.total_cmp(&b.0));
        lat.dedup_by(|a, b| a.0 == b.0);
        let rows = (0..p.v_angles.len())
            .map(|j| lat.iter().map(|&(_, i)| p.candela[i][j]).collect())
            .collect();
        return (p.v_angles.clone(), lat.iter().map(|l| l.0).collect(), rows);
    }
    let mut planes: Vec<(f64, Vec<f64>)> = p
        .h_angles
        .iter()
        .copied()
        .zip(p.candela.iter().cloned())
        .collect();
    let mirror = |planes: &mut Vec<(f64, Vec<f64>)>, f: &dyn Fn(f64) -> f64| {
        let extra: Vec<(f64, Vec<f64>)> = planes.iter().map(|(a, r)| (f(*a), r.clone())).collect();
        planes.extend(extra);
    };
    match p.kind {
        PhotometricType::C => match p.symmetry() {
            Symmetry::Rotational => {
                let r = planes[0].1.clone();
                planes = vec![(0.0, r.clone()), (360.0, r)];
            }
            Symmetry::Quadrant => {
                mirror(&mut planes, &|a| 180.0 - a);
                mirror(&mut planes, &|a| 360.0 - a);
            }
            Symmetry::BilateralC0 => mirror(&mut planes, &|a| 360.0 - a),
            Symmetry::BilateralC90 => {
                // C(phi) = C(180 - phi): the stored C90-C270 half gives the
                // rest (180 -> 0, 135 -> 45, 225 -> 315, ...). Without a
                // stored C180 no mirrored plane lands on C0: the turn is
                // closed across it.
                mirror(&mut planes, &|a| (540.0 - a) % 360.0);
                close_turn(&mut planes);
            }
            Symmetry::None => close_turn(&mut planes),
        },
        PhotometricType::A => {
            if p.h_angles.first().is_some_and(|&a| a >= 0.0) && p.h_angles.len() > 1 {
                mirror(&mut planes, &|a| -a);
            } else if p.h_angles.len() == 1 {
                let r = planes[0].1.clone();
                planes = vec![(-90.0, r.clone()), (90.0, r)];
            }
        }
        PhotometricType::B => unreachable!("transposed above"),
    }
    planes.sort_by(|a, b| a.0.total_cmp(&b.0));
    planes.dedup_by(|a, b| a.0 == b.0);
    let (h, rows) = planes.into_iter().unzip();
    (h, p.v_angles.clone(), rows)
}

/// Give the planes of a periodic type C table (angles in `[0, 360]`, at
/// least one) the planes C0 and C360 where they lack them: the row at C0
/// is the linear interpolation across it between the last plane and the
/// first one (a turn on), so the interpolant, periodic in C, is the one
/// the stored planes define, and C360 repeats C0.
fn close_turn(planes: &mut Vec<(f64, Vec<f64>)>) {
    planes.sort_by(|a, b| a.0.total_cmp(&b.0));
    planes.dedup_by(|a, b| a.0 == b.0);
    let (Some(first), Some(last)) = (planes.first(), planes.last()) else {
        return;
    };
    let (a0, a1) = (first.0, last.0);
    if a0 == 0.0 && a1 == 360.0 {
        return;
    }
    let row0 = if a0 == 0.0 {
        first.1.clone()
    } else if a1 == 360.0 {
        last.1.clone()
    } else {
        // From the last plane (at a1 - 360) to the first (at a0).
        let t = (360.0 - a1) / (a0 + 360.0 - a1);
        last.1
            .iter()
            .zip(&first.1)
            .map(|(l, f)| l + t * (f - l))
            .collect()
    };
    if a0 != 0.0 {
        planes.insert(0, (0.0, row0.clone()));
    }
    if a1 != 360.0 {
        planes.push((360.0, row0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::photometry::{Opening, ies, ldt};

    /// `int I dOmega` by the midpoint rule on an `n x 2n` grid in (cos theta, phi)
    /// over the whole sphere: independent of the cell integration above.
    fn quadrature(g: &Goniometric, n: usize) -> f64 {
        let mut sum = 0.0;
        for a in 0..n {
            let z = -1.0 + 2.0 * (a as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            for b in 0..2 * n {
                let phi = PI * (b as f64 + 0.5) / n as f64;
                sum += g.intensity(DVec3::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        sum * (2.0 / n as f64) * (PI / n as f64)
    }

    pub(super) fn table(
        kind: PhotometricType,
        h: &[f64],
        v: &[f64],
        f: impl Fn(f64, f64) -> f64,
    ) -> Photometry {
        Photometry {
            kind,
            v_angles: v.to_vec(),
            h_angles: h.to_vec(),
            candela: h
                .iter()
                .map(|&a| v.iter().map(|&b| f(a, b)).collect())
                .collect(),
            lamp_lumens: None,
            opening: Opening::default(),
            watts: None,
            format: "test".into(),
            tilt: None,
        }
    }

    pub(super) fn tables() -> Vec<(&'static str, Photometry)> {
        let g: Vec<f64> = (0..=18).map(|k| k as f64 * 5.0).collect(); // downlight 0-90
        let full: Vec<f64> = (0..=36).map(|k| k as f64 * 5.0).collect();
        let asym = |c: f64, gm: f64| 100.0 + 50.0 * (c.to_radians()).cos() + gm;
        vec![
            ("pendant", ies::parse(ies::tests::PENDANT, "p.ies").unwrap()),
            (
                "quadrant downlight",
                table(PhotometricType::C, &[0.0, 30.0, 60.0, 90.0], &g, |c, gm| {
                    (300.0 - 3.0 * gm)
                        * (1.0 + 0.2 * (2.0 * c.to_radians()).cos() * gm.to_radians().sin())
                }),
            ),
            (
                "bilateral C0",
                table(
                    PhotometricType::C,
                    &[0.0, 45.0, 90.0, 135.0, 180.0],
                    &full,
                    asym,
                ),
            ),
            (
                "bilateral C90",
                table(
                    PhotometricType::C,
                    &[90.0, 135.0, 180.0, 225.0, 270.0],
                    &full,
                    asym,
                ),
            ),
            (
                "bilateral C90 without C180",
                table(
                    PhotometricType::C,
                    &[90.0, 150.0, 210.0, 270.0],
                    &full,
                    asym,
                ),
            ),
            (
                "no symmetry",
                table(PhotometricType::C, &[0.0, 90.0, 180.0, 270.0], &full, asym),
            ),
            (
                "type B",
                table(
                    PhotometricType::B,
                    &[0.0, 20.0, 40.0, 90.0],
                    &[-90.0, -30.0, 0.0, 30.0, 90.0],
                    |h, v| 500.0 - 4.0 * h - 2.0 * v.abs(),
                ),
            ),
            (
                "type A",
                table(
                    PhotometricType::A,
                    &[-90.0, 0.0, 90.0],
                    &[-60.0, 0.0, 60.0],
                    |h, v| 100.0 + h + v,
                ),
            ),
        ]
    }

    #[test]
    fn power_is_the_integral_of_the_interpolated_intensity() {
        for (name, p) in tables() {
            let g = Goniometric::new(&p, 1.0);
            let q = quadrature(&g, 1000);
            assert!(
                (g.power() / q - 1.0).abs() < 2e-4,
                "{name}: power {} vs quadrature {q}",
                g.power()
            );
        }
    }

    /// A table symmetric about C90-C270 (first plane 90, last 270, LM-63)
    /// need not store C180: planes 90, 150, 210, 270 of 100, 120, 180,
    /// 200 cd at every gamma over 0-90. Mirrored (C -> 180 - C) they stand
    /// at 30 (120 cd), 90, 150, 210, 270 and 330 (180 cd), and C0 lies half
    /// way from C330 to C390 = C30: 150 cd, as C180 does half way from
    /// C150 to C210. By hand, the mean over the turn of the piecewise
    /// linear intensity is 54000 / 360 = 150 cd, so the flux over the
    /// lower hemisphere is 150 x 2 pi lm; at C15, (150 + 120) / 2 = 135 cd.
    /// (The turn was left open at C0 before: 785.4 lm, and 0 cd at C0.)
    #[test]
    fn a_c90_c270_table_without_c180_closes_the_turn() {
        let g: Vec<f64> = (0..=6).map(|k| k as f64 * 15.0).collect();
        let value = |c: f64| match c as i64 {
            90 => 100.0,
            150 => 120.0,
            210 => 180.0,
            _ => 200.0,
        };
        let p = table(
            PhotometricType::C,
            &[90.0, 150.0, 210.0, 270.0],
            &g,
            |c, _| value(c),
        );
        assert_eq!(p.symmetry(), Symmetry::BilateralC90);
        let gon = Goniometric::new(&p, 1.0);
        assert!(
            (gon.power() / (150.0 * 2.0 * PI) - 1.0).abs() < 1e-12,
            "{}",
            gon.power()
        );
        for (c, want) in [(0.0, 150.0), (15.0, 135.0), (180.0, 150.0), (345.0, 165.0)] {
            let got = gon.intensity_at(f64::to_radians(c), f64::to_radians(40.0));
            assert!((got - want).abs() < 1e-9, "C{c}: {got} cd, not {want}");
            let d = gon.direction(f64::to_radians(c), f64::to_radians(40.0));
            assert!((gon.intensity(d) - want).abs() < 1e-9, "C{c}: by direction");
        }
    }

    /// An IES type C table over 0-350 degrees is a full turn that wraps
    /// from C350 to C360 = C0: planes 0, 90, 180, 270, 350 with values
    /// `100 + C / 10`, `50 + C / 10`, 10 at gamma 0, 45, 90. By hand, at
    /// C355 (half way from C350 to C0), gamma 45: (85 + 50) / 2 = 67.5; at
    /// C352.5, gamma 22.5: (126.25 + 76.25) / 2 = 101.25 (off the pole,
    /// where every plane meets). The
    /// same table written out to 360 (C360 repeating C0) gives the same
    /// intensities and flux.
    #[test]
    fn a_table_to_350_degrees_wraps_to_c0() {
        let file = |h: &[f64]| {
            let rows: Vec<String> = h
                .iter()
                .map(|&c| {
                    let c = if c == 360.0 { 0.0 } else { c };
                    format!("{} {} 10", 100.0 + c / 10.0, 50.0 + c / 10.0)
                })
                .collect();
            let hs: Vec<String> = h.iter().map(|c| c.to_string()).collect();
            format!(
                "IESNA:LM-63-2002\n[TEST] x\nTILT=NONE\n1 -1 1 3 {} 1 2 0 0 0\n1 1 0\n0 45 90\n{}\n{}\n",
                h.len(),
                hs.join(" "),
                rows.join("\n")
            )
        };
        let p350 = ies::parse(&file(&[0.0, 90.0, 180.0, 270.0, 350.0]), "a.ies").unwrap();
        let p360 = ies::parse(&file(&[0.0, 90.0, 180.0, 270.0, 350.0, 360.0]), "b.ies").unwrap();
        assert_eq!(p350.symmetry(), Symmetry::None);
        let (a, b) = (Goniometric::new(&p350, 1.0), Goniometric::new(&p360, 1.0));
        for (c, gm, want) in [
            (355.0f64, 45.0f64, 67.5),
            (355.0, 90.0, 10.0),
            (352.5, 22.5, 101.25),
            (350.0, 45.0, 85.0),
            (0.0, 45.0, 50.0),
            (300.0, 45.0, 50.0 + 27.0 + 3.0 / 8.0 * 8.0),
        ] {
            let d = a.direction(c.to_radians(), gm.to_radians());
            for g in [&a, &b] {
                let (i, j) = (
                    g.intensity(d),
                    g.intensity_at(c.to_radians(), gm.to_radians()),
                );
                assert!(
                    (i - want).abs() < 1e-9 && (j - want).abs() < 1e-9,
                    "C{c} g{gm}: {i}, {j} vs {want}"
                );
            }
        }
        let mut rng = crate::sampling::Philox4x32::new(11, 0);
        for _ in 0..5000 {
            let d = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
            assert!((a.intensity(d) - b.intensity(d)).abs() < 1e-9, "{d}");
        }
        assert!((a.power() / b.power() - 1.0).abs() < 1e-12);
        // 0 to 170 is no known layout (neither a half nor a full turn).
        let e = ies::parse(&file(&[0.0, 90.0, 170.0]), "c.ies").unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (7, "horizontal angles"), "{e}");
    }

    #[test]
    fn nodes_are_reproduced_and_nothing_is_emitted_outside_the_measured_range() {
        let (_, p) = tables().swap_remove(1);
        let g = Goniometric::new(&p, 2.0);
        for (a, &c) in p.h_angles.iter().enumerate() {
            for (k, &gm) in p.v_angles.iter().enumerate() {
                let d = g.direction(c.to_radians(), gm.to_radians());
                let i = g.intensity(d);
                assert!(
                    (i - 2.0 * p.candela[a][k]).abs() < 1e-9 * i.max(1.0),
                    "C{c} g{gm}: {i}"
                );
            }
        }
        // Quadrant symmetry: C300 = C60, C120 = C60, C200 = C20.
        for (x, y) in [(300.0f64, 60.0f64), (120.0, 60.0), (200.0, 20.0)] {
            let (a, b) = (
                g.intensity_at(x.to_radians(), 0.5),
                g.intensity_at(y.to_radians(), 0.5),
            );
            assert!((a - b).abs() < 1e-9 * b, "{x} vs {y}");
        }
        // Measured 0-90: nothing goes up, however close to the horizon.
        assert_eq!(g.intensity(DVec3::new(1.0, 0.0, 1e-9).normalize()), 0.0);
        assert_eq!(g.intensity(DVec3::Z), 0.0);
        assert!(g.intensity(DVec3::new(1.0, 0.0, -1e-9).normalize()) > 0.0);
        // Half the sphere: the flux of the lower hemisphere only.
        let q = quadrature(&g, 1000);
        assert!((g.power() / q - 1.0).abs() < 2e-4);
    }

    /// Type B reads the file's `V` as the plane's angle about the
    /// transverse axis `y` and `H` as the lateral angle out of it, `d =
    /// (cos H sin V, sin H, -cos H cos V)` (LM-63, Radiance's `ies2rad`);
    /// type A reads `H` as the plane's angle about `x` and `V` as the angle
    /// out of it, `d = (sin V, cos V sin H, -cos V cos H)` (`H` horizontal
    /// and `V` vertical for a luminaire aimed level in both). A table of
    /// `I = f(H, V)`, bilinear in the two so that the interpolant is `f`
    /// itself, reads `f` in those directions at random angles (the other
    /// reading gives other values wherever `f(H, V) != f(V, H)`); a file
    /// from `H = 0` gives `I(-H) = I(H)`; the power is the sphere's
    /// quadrature.
    #[test]
    fn types_a_and_b_read_their_planes_and_angles_out_of_them() {
        let f = |h: f64, v: f64| 1000.0 + 5.0 * h + 2.0 * v + 0.02 * h * v;
        let hs = [-90.0, -40.0, -10.0, 0.0, 25.0, 60.0, 90.0];
        let vs = [-90.0, -50.0, 0.0, 30.0, 70.0, 90.0];
        let mut rng = crate::sampling::Philox4x32::new(5, 0);
        for kind in [PhotometricType::B, PhotometricType::A] {
            let g = Goniometric::new(&table(kind, &hs, &vs, f), 1.0);
            for _ in 0..2000 {
                let u = rng.next_2d();
                // Off the poles (H = +-90 for type B, V = +-90 for type A).
                let (h, v) = (178.0 * u[0] - 89.0, 178.0 * u[1] - 89.0);
                let (sh, ch) = h.to_radians().sin_cos();
                let (sv, cv) = v.to_radians().sin_cos();
                let d = match kind {
                    PhotometricType::B => DVec3::new(ch * sv, sh, -ch * cv),
                    _ => DVec3::new(sv, cv * sh, -cv * ch),
                };
                let (got, want) = (g.intensity(d), f(h, v));
                assert!(
                    (got - want).abs() < 1e-9 * want,
                    "{kind:?} H{h} V{v}: {got} vs {want}"
                );
            }
            assert!((g.power() / quadrature(&g, 1000) - 1.0).abs() < 2e-4);
            // Nothing behind the beam's hemisphere (V and H within +-90).
            assert_eq!(g.intensity(DVec3::new(0.3, 0.2, 0.9).normalize()), 0.0);
        }
        let half = [0.0, 30.0, 60.0, 90.0];
        for kind in [PhotometricType::B, PhotometricType::A] {
            let g = Goniometric::new(&table(kind, &half, &vs, f), 1.0);
            for (h, v) in [(30.0f64, 20.0f64), (45.0, -60.0), (80.0, 85.0)] {
                let at = |h: f64| {
                    let (sh, ch) = h.to_radians().sin_cos();
                    let (sv, cv) = v.to_radians().sin_cos();
                    g.intensity(match kind {
                        PhotometricType::B => DVec3::new(ch * sv, sh, -ch * cv),
                        _ => DVec3::new(sv, cv * sh, -cv * ch),
                    })
                };
                let want = f(h, v);
                let ok = |x: f64| (x - want).abs() < 1e-9 * want;
                assert!(ok(at(h)) && ok(at(-h)), "{kind:?} H{h} V{v}");
            }
        }
    }

    #[test]
    fn sampling_weights_average_to_the_power_and_follow_the_pdf() {
        use crate::sampling::Philox4x32;
        for (name, p) in tables() {
            let g = Goniometric::new(&p, 1.0);
            let mut rng = Philox4x32::new(7, 0);
            let n = 200_000;
            let (mut s, mut s2) = (0.0, 0.0);
            for _ in 0..n {
                let u = rng.next_2d();
                let e = g.sample(u, rng.next_f64()).unwrap();
                assert!((e.d.length() - 1.0).abs() < 1e-12);
                let pdf = g.pdf(e.d);
                assert!(
                    (pdf / e.pdf - 1.0).abs() < 1e-9,
                    "{name}: pdf {pdf} vs {}",
                    e.pdf
                );
                let w = e.i / e.pdf;
                s += w;
                s2 += w * w;
            }
            let mean = s / n as f64;
            let se = ((s2 / n as f64 - mean * mean) / n as f64).sqrt();
            let z = (mean - g.power()) / se;
            assert!(
                z.abs() < 4.5,
                "{name}: mean weight {mean} +- {se} vs power {} (z {z})",
                g.power()
            );
        }
    }

    #[test]
    fn an_ies_and_an_ldt_of_the_same_distribution_agree() {
        // C0-C180 bilateral, gamma 0-180 in 45 degree steps, values in cd.
        let rows: [[f64; 5]; 5] = [
            [400.0, 300.0, 100.0, 10.0, 0.0],
            [380.0, 280.0, 90.0, 10.0, 0.0],
            [360.0, 250.0, 80.0, 5.0, 0.0],
            [380.0, 270.0, 95.0, 10.0, 0.0],
            [400.0, 290.0, 100.0, 12.0, 0.0],
        ];
        let mut ies_text = String::from(
            "IESNA:LM-63-2002\n[TEST] pair\nTILT=NONE\n1 1000 1 5 5 1 2 0 0 0\n1 1 20\n0 45 90 135 180\n0 45 90 135 180\n",
        );
        for r in rows {
            ies_text += &format!("{}\n", r.map(|v| v.to_string()).join(" "));
        }
        // EULUMDAT in cd/klm for a 1000 lm lamp: the same numbers.
        let mut l = vec![
            "pair", "1", "2", "8", "45", "5", "45", "r", "n", "n", "f", "d", "0", "0", "0", "0",
            "0", "0", "0", "0", "0", "100", "100", "1", "0", "1", "1", "LED", "1000", "840", "1A",
            "20",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
        l.extend((0..10).map(|_| "0.5".to_string()));
        l.extend((0..8).map(|k| (k * 45).to_string()));
        l.extend((0..5).map(|k| (k * 45).to_string()));
        for r in rows {
            l.extend(r.map(|v| v.to_string()));
        }
        let a = Goniometric::new(&ies::parse(&ies_text, "p.ies").unwrap(), 1.0);
        let b = Goniometric::new(&ldt::parse(&l.join("\n"), "p.ldt").unwrap(), 1.0);
        assert!((a.power() / b.power() - 1.0).abs() < 1e-12);
        let mut rng = crate::sampling::Philox4x32::new(3, 1);
        for _ in 0..1000 {
            let d = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
            let (x, y) = (a.intensity(d), b.intensity(d));
            assert!((x - y).abs() <= 1e-12 * x.max(1.0), "{d}: {x} vs {y}");
        }
    }
}

#[cfg(test)]
mod fast_path_tests {
    use super::*;
    use crate::sampling::Philox4x32;

    /// The type C shortcut (cells without inverse trigonometry, no azimuth
    /// for rotational tables) gives the general bilinear rule's values to
    /// rounding, on every test table, at random directions and at the
    /// nodes, the poles and the edges of the measured range. The reference
    /// takes its angles by `atan2` (accurate at the poles, where
    /// `acos(-d_z)` loses half the digits); at a pole (within 1e-12 rad) it is the mean
    /// of `intensity_at` over 3600 equal steps of C (the midpoint rule, exact
    /// for the interpolant, linear between planes at whole degrees).
    #[test]
    fn shortcuts_agree_with_the_general_rule() {
        let mut checked = 0;
        for (name, p) in super::tests::tables() {
            let fast = Goniometric::new(&p, 1.0);
            assert_eq!(fast.grids.is_some(), p.kind == PhotometricType::C, "{name}");
            let mut dirs: Vec<DVec3> = Vec::new();
            let mut rng = Philox4x32::new(3, 0);
            for _ in 0..20_000 {
                dirs.push(crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w);
            }
            for &h in &fast.h {
                for &v in &fast.v {
                    for e in [-1e-9, 0.0, 1e-9] {
                        dirs.push(fast.direction(h + e, v + e));
                    }
                }
            }
            dirs.extend([
                DVec3::Z,
                -DVec3::Z,
                DVec3::X,
                -DVec3::X,
                DVec3::Y,
                -DVec3::Y,
            ]);
            for d in dirs {
                let (h, v) = match p.kind {
                    PhotometricType::C => {
                        let c = d.y.atan2(d.x);
                        let c = if c < 0.0 { c + 2.0 * PI } else { c };
                        (c, (d.x * d.x + d.y * d.y).sqrt().atan2(-d.z))
                    }
                    _ => fast.angles(d),
                };
                let pole = p.kind == PhotometricType::C && d.x.hypot(d.y) <= 1e-12 * d.length();
                let b = if pole {
                    (0..3600)
                        .map(|k| fast.intensity_at(((k as f64 + 0.5) / 10.0).to_radians(), v))
                        .sum::<f64>()
                        / 3600.0
                } else {
                    fast.intensity_at(h, v)
                };
                let a = fast.intensity(d);
                let tol = if pole { 1e-10 } else { 1e-12 };
                assert!(
                    (a - b).abs() <= tol * b.abs().max(1.0),
                    "{name} {d}: {a} vs {b}"
                );
                checked += 1;
            }
        }
        assert!(checked > 100_000);
    }

    /// At the poles, where every C-plane meets, the intensity of a
    /// direction is the planes' mean, whatever the sign of a zero
    /// component: planes C0, C60, C180, C270 (wrapping to C360 = C0) with
    /// 100, 200, 300, 400 cd at gamma 0 and a tenth of that at gamma 180.
    /// By hand, the mean over C of the interpolant: (60 x 150 + 120 x 250 +
    /// 90 x 350 + 90 x 250) / 360 = 258.333 cd at the nadir, 25.8333 cd at
    /// the zenith (before: C0's 100 or, for a negative zero x, C180's 300).
    #[test]
    fn pole_intensity_is_the_planes_mean() {
        let p = super::tests::table(
            PhotometricType::C,
            &[0.0, 60.0, 180.0, 270.0],
            &[0.0, 90.0, 180.0],
            |c, gm| {
                let at0 = match c as i32 {
                    0 => 100.0,
                    60 => 200.0,
                    180 => 300.0,
                    _ => 400.0,
                };
                at0 * (1.0 - 0.9 * gm / 180.0)
            },
        );
        let g = Goniometric::new(&p, 1.0);
        let (down, up) = (93_000.0 / 360.0, 9_300.0 / 360.0);
        assert!(matches!(g.grids, Some((_, Some(_)))));
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9 * b;
        for d in [
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(-0.0, 0.0, -1.0),
            DVec3::new(-0.0, -0.0, -1.0),
            DVec3::new(0.0, -0.0, -1.0),
        ] {
            assert!(close(g.intensity(d), down), "{d}: {}", g.intensity(d));
            assert!(close(g.intensity(-d), up), "{}: {}", -d, g.intensity(-d));
        }
        // The same in the world: straight along a tilted nadir, by the
        // direct term (I c / |w|^3 at 2 m, facing the light: I / 4).
        let frame = super::super::LuminaireFrame::aimed(DVec3::new(0.3, -0.2, -1.0), 0.7);
        for (w, want) in [(-2.0 * frame.z, down), (2.0 * frame.z, up)] {
            let e = g.direct_term(&frame, w, 2.0);
            assert!(close(e, want / 4.0), "{w}: {e}");
        }
        // Off the pole, plane by plane as before: C60 at gamma 1e-9 deg.
        let d = g.direction(60f64.to_radians(), 1e-9f64.to_radians());
        assert!((g.intensity(d) - 200.0).abs() < 1e-6);
        // Measured 0-90 only: nothing straight up.
        let half = super::tests::table(
            PhotometricType::C,
            &[0.0, 60.0, 180.0, 270.0],
            &[0.0, 90.0],
            |c, _| 100.0 + c,
        );
        assert_eq!(Goniometric::new(&half, 1.0).intensity(DVec3::Z), 0.0);
    }

    /// The world-frame shortcut of rotational tables equals the intensity
    /// of the local direction, in tilted and turned frames.
    #[test]
    fn world_shortcut_agrees_with_the_local_direction() {
        let (_, p) = super::tests::tables().swap_remove(0);
        let g = Goniometric::new(&p, 1.0);
        assert!(matches!(g.grids, Some((_, None))));
        let mut rng = Philox4x32::new(9, 0);
        for aim in [
            -DVec3::Z,
            DVec3::new(0.3, -0.2, -1.0),
            DVec3::X,
            DVec3::new(-1.0, 2.0, 0.5),
        ] {
            let frame = super::super::LuminaireFrame::aimed(aim, 0.7);
            for _ in 0..5000 {
                let w = crate::sampling::warp::sample_uniform_sphere(rng.next_2d()).w;
                let (a, b) = (g.intensity_world(&frame, w), g.intensity(frame.to_local(w)));
                assert!((a - b).abs() <= 1e-12 * b.max(1.0), "{aim} {w}: {a} vs {b}");
            }
            // The direct term: I cos / d^2 by hand, with I from the
            // inverse-trigonometric rule (acos, atan2: no AngleGrid), at
            // receivers on all sides: the rotational, the asymmetric (full
            // C0-C360 after expansion) and the 0-90 degree quadrant tables,
            // whose fast paths differ.
            let tables = super::tests::tables();
            let quadrant = Goniometric::new(&tables[1].1, 1.0);
            let bilateral = Goniometric::new(&tables[2].1, 1.0);
            assert!(matches!(quadrant.grids, Some((_, Some(_)))));
            assert!(matches!(bilateral.grids, Some((_, Some(_)))));
            for g in [&g, &quadrant, &bilateral] {
                for j in 0..3000 {
                    let u = rng.next_2d();
                    let z = [-1.5, 0.7, -0.2][j % 3];
                    let w = DVec3::new(4.0 * u[0] - 2.0, 4.0 * u[1] - 2.0, z);
                    let c = 0.8 * w.length();
                    let (h, v) = g.angles(frame.to_local(w.normalize()));
                    let want = g.intensity_at(h, v) * c / w.length_squared() / w.length();
                    let got = g.direct_term(&frame, w, c);
                    assert!(
                        (got - want).abs() <= 1e-9 * want.abs().max(1e-300),
                        "{w}: {got} vs {want}"
                    );
                }
                // Poles: the intensity of the local pole direction (the
                // planes' mean there, checked in pole_intensity_is_the_planes_mean).
                for w in [frame.z, -frame.z, -2.0 * frame.z] {
                    let local = if w.dot(frame.z) > 0.0 {
                        DVec3::Z
                    } else {
                        -DVec3::Z
                    };
                    let want = g.intensity(local) / w.length_squared();
                    let got = g.direct_term(&frame, w, w.length());
                    assert!(
                        (got - want).abs() <= 1e-9 * want.max(1e-300),
                        "{w}: {got} vs {want}"
                    );
                }
                assert_eq!(g.direct_term(&frame, DVec3::ZERO, 0.0), 0.0);
            }
            // Straight down the nadir: the gamma = 0 value.
            let nadir = g.intensity_world(&frame, aim.normalize());
            assert!((nadir - 879.2).abs() < 1e-9, "{nadir}");
        }
    }
}
