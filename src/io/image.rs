//! Luminance images: Radiance HDR, display PNG, false-colour PNG with a
//! labelled scale bar, and polar plots of L(theta, phi) over a hemisphere.
//!
//! Every pixel value is a luminance in [cd/m^2]. Images are encoded to
//! memory first and written with [`write_atomic`], so a reader never sees a
//! half-written file. Non-finite values never reach an encoder: they are an
//! error when the data are checked (at construction and again before each
//! write, since the fields are public).
//!
//! Text (tick labels, titles) is drawn by plotters with a font embedded in
//! the binary (see `io/text.rs`), so nothing depends on system fonts.

use super::csvio::write_atomic;
use ::image::codecs::hdr::HdrEncoder;
use ::image::codecs::png::PngEncoder;
use ::image::{ExtendedColorType, ImageEncoder};
use std::f64::consts::{FRAC_PI_2, TAU};

/// A bad image, bad plot data, or a failed encode or write.
#[derive(Debug, thiserror::Error)]
pub enum ImageIoError {
    /// The data cannot be turned into an image (sizes, NaN, negatives, ...).
    #[error("invalid image data: {0}")]
    Invalid(String),
    /// The encoder refused the data.
    #[error("{path}: cannot encode: {message}")]
    Encode { path: String, message: String },
    /// The file could not be written (the operating system's reason is
    /// part of the message, not an error source, so `{:#}` prints it once).
    #[error("{path}: cannot write: {reason}")]
    Write {
        path: String,
        reason: std::io::Error,
    },
}

type Result<T> = std::result::Result<T, ImageIoError>;

fn invalid<T>(message: impl Into<String>) -> Result<T> {
    Err(ImageIoError::Invalid(message.into()))
}

/// Negatives down to this fraction of the largest value (in magnitude) are
/// round-off and are set to 0; anything more negative is an error.
pub const NEGATIVE_TOLERANCE: f64 = 1e-12;

/// Check luminances: every value finite; negatives within
/// [`NEGATIVE_TOLERANCE`] of the largest positive value clamped to 0 (as is
/// `-0.0`); real negatives rejected. `what(i)` names value `i` in messages.
fn clean_values(values: &[f64], what: impl Fn(usize) -> String) -> Result<Vec<f64>> {
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return invalid(format!(
            "{} is {} (luminance must be finite)",
            what(i),
            values[i]
        ));
    }
    let max = values.iter().fold(0.0_f64, |m, &v| m.max(v));
    let floor = -NEGATIVE_TOLERANCE * max;
    let mut out = Vec::with_capacity(values.len());
    for (i, &v) in values.iter().enumerate() {
        if v < floor {
            return invalid(format!(
                "{} is {v} cd/m^2 (luminance cannot be negative; only round-off \
                 down to -{NEGATIVE_TOLERANCE:e} x the largest value is clamped to 0)",
                what(i)
            ));
        }
        out.push(v.max(0.0));
    }
    Ok(out)
}

/// A luminance image: `width x height` pixels, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct LuminanceImage {
    /// Pixels per row.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// Luminance of each pixel [cd/m^2], `l[y * width + x]`, all finite and >= 0.
    pub l: Vec<f64>,
}

impl LuminanceImage {
    /// Check and build an image from row-major luminances [cd/m^2].
    ///
    /// Errors: a zero size, a length other than `width * height`, a
    /// non-finite value, or a negative value below round-off (see
    /// [`NEGATIVE_TOLERANCE`]); round-off negatives become 0.
    pub fn new(width: usize, height: usize, l: Vec<f64>) -> Result<Self> {
        let img = LuminanceImage { width, height, l };
        let l = img.checked_values()?;
        Ok(LuminanceImage { l, ..img })
    }

    /// Build an image from `f(x, y)` = luminance [cd/m^2] of pixel column
    /// `x`, row `y` (row 0 at the top), checked as in [`LuminanceImage::new`].
    pub fn from_fn(
        width: usize,
        height: usize,
        mut f: impl FnMut(usize, usize) -> f64,
    ) -> Result<Self> {
        let mut l = Vec::with_capacity(width.saturating_mul(height));
        for y in 0..height {
            for x in 0..width {
                l.push(f(x, y));
            }
        }
        Self::new(width, height, l)
    }

    /// Luminance [cd/m^2] of column `x`, row `y` (row 0 at the top).
    pub fn get(&self, x: usize, y: usize) -> f64 {
        self.l[y * self.width + x]
    }

    /// The checks of [`LuminanceImage::new`] on the current fields, returning
    /// the cleaned values (writers call this, as the fields are public).
    fn checked_values(&self) -> Result<Vec<f64>> {
        if self.width == 0 || self.height == 0 {
            return invalid(format!("empty image ({} x {})", self.width, self.height));
        }
        if self.width > u32::MAX as usize || self.height > u32::MAX as usize {
            return invalid(format!(
                "image too large ({} x {})",
                self.width, self.height
            ));
        }
        let n = self.width.checked_mul(self.height);
        if n != Some(self.l.len()) {
            return invalid(format!(
                "{} x {} image needs {} values, got {}",
                self.width,
                self.height,
                n.map_or("too many".into(), |n| n.to_string()),
                self.l.len()
            ));
        }
        let w = self.width;
        clean_values(&self.l, |i| format!("pixel (x={}, y={})", i % w, i / w))
    }
}

fn write_file(path: &str, bytes: &[u8]) -> Result<()> {
    write_atomic(path, bytes).map_err(|reason| ImageIoError::Write {
        path: path.to_string(),
        reason,
    })
}

fn encode_error(path: &str, e: impl std::fmt::Display) -> ImageIoError {
    ImageIoError::Encode {
        path: path.to_string(),
        message: e.to_string(),
    }
}

// ---------------------------------------------------------------------------
// Radiance HDR

/// Largest luminance an RGBE pixel can hold [cd/m^2] (exponent byte 255).
pub const HDR_MAX: f64 = 1.0e38;

/// Comment lines put into the header of every `.hdr` file written here.
const HDR_NOTE: &str = "\
# lumest: grey image, R = G = B = luminance L [cd/m^2] (photometric).\n\
# lumest: Radiance's own convention is radiance in W/sr/m^2 with L = 179 (0.265 R + 0.670 G + 0.065 B);\n\
# lumest: here the pixel value is L itself, so use a multiplier of 1, not 179 (e.g. falsecolor -m 1).\n";

/// Encode `img` as a Radiance RGBE `.hdr` file in memory (see [`write_hdr`]).
pub fn encode_hdr(img: &LuminanceImage) -> Result<Vec<u8>> {
    let l = img.checked_values()?;
    if let Some(i) = l.iter().position(|&v| v > HDR_MAX) {
        return invalid(format!(
            "pixel (x={}, y={}) is {} cd/m^2, beyond what RGBE can hold ({HDR_MAX:e})",
            i % img.width,
            i / img.width,
            l[i]
        ));
    }
    // The encoder truncates the 8-bit mantissa; adding half a mantissa step
    // first makes it round to nearest (relative error <= 1/256, not 1/128).
    // Values below the smallest normal f32 are flushed to 0.
    let pixels: Vec<::image::Rgb<f32>> = l
        .iter()
        .map(|&v| {
            let v = if v < f32::MIN_POSITIVE as f64 {
                0.0
            } else {
                let step = (v.log2().floor() + 1.0).exp2() / 256.0;
                (v + 0.5 * step) as f32
            };
            ::image::Rgb([v, v, v])
        })
        .collect();
    let mut bytes = Vec::new();
    HdrEncoder::new(&mut bytes)
        .encode(&pixels, img.width, img.height)
        .map_err(|e| ImageIoError::Encode {
            path: "<hdr>".into(),
            message: e.to_string(),
        })?;
    // Put our note after the signature line (`#?RADIANCE`); header lines
    // starting with '#' are comments to readers.
    let at = bytes.iter().position(|&b| b == b'\n').map_or(0, |p| p + 1);
    bytes.splice(at..at, HDR_NOTE.bytes());
    Ok(bytes)
}

/// Write `img` as a Radiance RGBE `.hdr` file (top row first, RLE scanlines).
///
/// The file is grey, R = G = B = L: each pixel value is the luminance
/// [cd/m^2] itself. Radiance's own convention is radiance in W/sr/m^2, from
/// which its tools compute luminance as 179 (0.265 R + 0.670 G + 0.065 B);
/// here we store photometric luminance directly, so with Radiance tools use a
/// multiplier of 1 instead of 179 (a header comment says so). RGBE keeps an
/// 8-bit mantissa: values come back within a relative 1/256 (rounded to
/// nearest). Values below ~1.2e-38 are stored as 0; above [`HDR_MAX`] is an error.
pub fn write_hdr(img: &LuminanceImage, path: &str) -> Result<()> {
    let bytes = encode_hdr(img).map_err(|e| match e {
        ImageIoError::Encode { message, .. } => encode_error(path, message),
        e => e,
    })?;
    write_file(path, &bytes)
}

// ---------------------------------------------------------------------------
// Display PNG

/// How luminance [cd/m^2] becomes a display value (1.0 = white) before the
/// sRGB transfer function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    /// Display value = L / L99, where L99 is the [`AUTO_PERCENTILE`]
    /// (nearest-rank) luminance of the image: L99 shows as white and at most
    /// 1% of the pixels clip. If L99 is 0 the maximum is used instead; an
    /// all-black image gets a multiplier of 1.
    Auto,
    /// Display value = L * k with `k` [m^2/cd] finite and > 0; 1.0 = white.
    Fixed(f64),
}

/// The percentile mapped to white by [`Exposure::Auto`].
pub const AUTO_PERCENTILE: f64 = 0.99;

/// The multiplier k [m^2/cd] of `exposure` for `img` (display value = L k).
pub fn exposure_multiplier(img: &LuminanceImage, exposure: Exposure) -> Result<f64> {
    let l = img.checked_values()?;
    multiplier_of(&l, exposure)
}

fn multiplier_of(l: &[f64], exposure: Exposure) -> Result<f64> {
    match exposure {
        Exposure::Fixed(k) if k.is_finite() && k > 0.0 => Ok(k),
        Exposure::Fixed(k) => invalid(format!("exposure multiplier {k} must be finite and > 0")),
        Exposure::Auto => {
            let mut s = l.to_vec();
            s.sort_by(f64::total_cmp);
            let rank =
                ((AUTO_PERCENTILE * s.len() as f64 - 1e-9).ceil() as usize).clamp(1, s.len());
            let p = s[rank - 1];
            let max = s[s.len() - 1];
            Ok(if p > 0.0 {
                1.0 / p
            } else if max > 0.0 {
                1.0 / max
            } else {
                1.0
            })
        }
    }
}

/// The sRGB transfer function (IEC 61966-2-1): linear display value in
/// [0, 1] -> encoded value in [0, 1]; input clamped to [0, 1].
pub fn srgb_encode(v: f64) -> f64 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The 8-bit display byte of luminance `l` [cd/m^2] under multiplier `k`
/// [m^2/cd]: `round(255 srgb_encode(l k))`.
pub fn display_byte(l: f64, k: f64) -> u8 {
    (255.0 * srgb_encode(l * k) + 0.5).floor() as u8
}

/// Write `img` as an 8-bit grey sRGB PNG for viewing: display value
/// `L k` (k from `exposure`, 1.0 = white), the sRGB transfer function,
/// clamped to [0, 1], rounded to 8 bits.
pub fn write_display_png(img: &LuminanceImage, path: &str, exposure: Exposure) -> Result<()> {
    let l = img.checked_values()?;
    let k = multiplier_of(&l, exposure)?;
    let grey: Vec<u8> = l.iter().map(|&v| display_byte(v, k)).collect();
    let mut bytes = Vec::new();
    PngEncoder::new(&mut bytes)
        .write_image(
            &grey,
            img.width as u32,
            img.height as u32,
            ExtendedColorType::L8,
        )
        .map_err(|e| encode_error(path, e))?;
    write_file(path, &bytes)
}

// ---------------------------------------------------------------------------
// Colour map and scale

/// Viridis (matplotlib's perceptually uniform map, CC0), 17 equally spaced
/// samples as 8-bit sRGB; dark purple (low) to yellow (high), lightness
/// increasing throughout.
const VIRIDIS: [[u8; 3]; 17] = [
    [0x44, 0x01, 0x54],
    [0x48, 0x18, 0x6a],
    [0x47, 0x2d, 0x7b],
    [0x42, 0x40, 0x86],
    [0x3b, 0x52, 0x8b],
    [0x33, 0x63, 0x8d],
    [0x2c, 0x72, 0x8e],
    [0x26, 0x82, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x1f, 0xa0, 0x88],
    [0x28, 0xae, 0x80],
    [0x3f, 0xbc, 0x73],
    [0x5e, 0xc9, 0x62],
    [0x84, 0xd4, 0x4b],
    [0xad, 0xdc, 0x30],
    [0xd8, 0xe2, 0x19],
    [0xfd, 0xe7, 0x25],
];

/// The colour map: `t` in [0, 1] (clamped; NaN -> 0) to 8-bit sRGB, by
/// linear interpolation in a 17-entry viridis table. `colour_map(0.0)` is the
/// first (dark purple) entry, `colour_map(1.0)` the last (yellow).
pub fn colour_map(t: f64) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let u = t * (VIRIDIS.len() - 1) as f64;
    let i = (u.floor() as usize).min(VIRIDIS.len() - 2);
    let f = u - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    std::array::from_fn(|c| (a[c] as f64 + f * (b[c] as f64 - a[c] as f64)).round() as u8)
}

/// Decades below the maximum covered by [`ColourScale::from_data`] on a log scale.
pub const LOG_DECADES: f64 = 3.0;

/// The luminance range [cd/m^2] of a false-colour map: `min` gets the first
/// colour, `max` the last; values outside are clamped to the ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColourScale {
    /// Luminance of the first colour [cd/m^2]; > 0 when `log`.
    pub min: f64,
    /// Luminance of the last colour [cd/m^2]; > `min`.
    pub max: f64,
    /// Logarithmic (`true`) or linear spacing between `min` and `max`.
    pub log: bool,
}

impl ColourScale {
    /// A scale picked from the finite values in `values` [cd/m^2]. Linear:
    /// from the smallest to the largest value. Log: from [`LOG_DECADES`]
    /// decades below the largest value up to it. Degenerate data (no finite
    /// values, all equal, nothing positive for a log scale) fall back to a
    /// range around the data, or [1e-3, 1] / [0, 1] when there is none.
    pub fn from_data(values: &[f64], log: bool) -> Self {
        let finite = values.iter().copied().filter(|v| v.is_finite());
        let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        if log {
            if hi > 0.0 {
                ColourScale {
                    min: hi / 10f64.powf(LOG_DECADES),
                    max: hi,
                    log,
                }
            } else {
                ColourScale {
                    min: 1e-3,
                    max: 1.0,
                    log,
                }
            }
        } else if lo < hi {
            ColourScale {
                min: lo,
                max: hi,
                log,
            }
        } else if lo.is_finite() && lo != 0.0 {
            let d = 0.5 * lo.abs();
            ColourScale {
                min: lo - d,
                max: lo + d,
                log,
            }
        } else {
            ColourScale {
                min: 0.0,
                max: 1.0,
                log,
            }
        }
    }

    /// Check the scale: finite ends, `min < max`, `min > 0` when `log`.
    pub fn validate(&self) -> Result<()> {
        if !(self.min.is_finite() && self.max.is_finite() && self.min < self.max) {
            return invalid(format!(
                "colour scale [{}, {}] needs finite ends with min < max",
                self.min, self.max
            ));
        }
        if self.log && self.min <= 0.0 {
            return invalid(format!("log colour scale needs min > 0 (got {})", self.min));
        }
        Ok(())
    }

    /// Position of luminance `l` [cd/m^2] on the scale, clamped to [0, 1]
    /// (0 at `min`, 1 at `max`; on a log scale l <= 0 gives 0).
    pub fn fraction(&self, l: f64) -> f64 {
        let f = if self.log {
            if l <= 0.0 {
                return 0.0;
            }
            (l / self.min).ln() / (self.max / self.min).ln()
        } else {
            (l - self.min) / (self.max - self.min)
        };
        if f.is_nan() { 0.0 } else { f.clamp(0.0, 1.0) }
    }

    /// The colour of luminance `l` [cd/m^2]: `colour_map(fraction(l))`.
    pub fn colour(&self, l: f64) -> [u8; 3] {
        colour_map(self.fraction(l))
    }

    /// Candidate tick values, at most about `n` of them (before thinning).
    fn ticks(&self, n: usize) -> Vec<f64> {
        let n = n.max(2);
        let mut t = Vec::new();
        if self.log {
            let (a, b) = (self.min.log10(), self.max.log10());
            let (k0, k1) = ((a - 1e-9).ceil() as i32, (b + 1e-9).floor() as i32);
            let decades = (k1 - k0 + 1).max(0) as usize;
            let every = decades.div_ceil(n).max(1);
            for k in (k0..=k1).filter(|k| ((k - k0) as usize).is_multiple_of(every)) {
                t.push(10f64.powi(k));
            }
            if t.len() < 3 {
                for k in (k0 - 1)..=k1 {
                    for m in [2.0, 5.0] {
                        let v = m * 10f64.powi(k);
                        if v >= self.min * (1.0 - 1e-9) && v <= self.max * (1.0 + 1e-9) {
                            t.push(v);
                        }
                    }
                }
            }
        } else {
            let raw = (self.max - self.min) / n as f64;
            let mag = 10f64.powf(raw.log10().floor());
            let step = [1.0, 2.0, 5.0, 10.0]
                .into_iter()
                .map(|m| m * mag)
                .find(|&s| s >= raw * (1.0 - 1e-9))
                .unwrap_or(10.0 * mag);
            let k0 = (self.min / step - 1e-9).ceil() as i64;
            let k1 = (self.max / step + 1e-9).floor() as i64;
            for k in k0..=k1 {
                let v = k as f64 * step;
                // Snap round-off (0.30000000000000004) and exact zero.
                t.push(if v.abs() < 1e-9 * step { 0.0 } else { v });
            }
        }
        if t.len() < 2 {
            t = vec![self.min, self.max];
        }
        t.sort_by(f64::total_cmp);
        t.dedup();
        t
    }
}

/// Short text of a tick value: up to 3 significant digits, plain decimals
/// between 1e-3 and 1e5, otherwise `1.5e-7` style.
pub fn tick_label(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        return "0".into();
    }
    if (1e-3..1e5).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).clamp(0, 6) as usize;
        trim_zeros(format!("{x:.decimals$}"))
    } else {
        let s = format!("{x:.2e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{e}", trim_zeros(m.to_string()))
    }
}

/// Text of a value on a scale whose marks lie `res` apart (isolux levels,
/// colour-bar ticks): [`tick_label`]'s style, with as many digits as it
/// takes to tell marks `res` apart. (Three significant digits labelled the
/// 199.5 lx isoline "200" and the bar's ticks from 198.6 to 199.8 "199".)
pub fn label_to(x: f64, res: f64) -> String {
    if !(res > 0.0 && res.is_finite()) || x == 0.0 || !x.is_finite() {
        return tick_label(x);
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        // Decimals of a 1-2-5 step (the first power of ten that makes it
        // whole), else enough for its first digit.
        let need = (0..=12)
            .find(|&d| {
                let s = res * 10f64.powi(d);
                (s - s.round()).abs() <= 1e-6 * s
            })
            .unwrap_or_else(|| (-res.log10()).ceil().max(0.0) as i32);
        let sig = 2 - a.log10().floor() as i32;
        let decimals = need.max(sig).clamp(0, 12) as usize;
        trim_zeros(format!("{x:.decimals$}"))
    } else {
        let digits = ((a / res).log10().ceil() as i32).clamp(2, 15) as usize;
        let s = format!("{x:.digits$e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{e}", trim_zeros(m.to_string()))
    }
}

/// `s` without the trailing zeros of its decimals (and a bare point).
fn trim_zeros(s: String) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

// ---------------------------------------------------------------------------
// Raster and text

/// An 8-bit sRGB raster, row-major, row 0 at the top, 3 bytes per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb8Image {
    /// Pixels per row.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// `[r, g, b]` of pixel (x, y) at `3 * (y * width + x)`.
    pub data: Vec<u8>,
}

const WHITE: [u8; 3] = [255, 255, 255];
const INK: [u8; 3] = [0, 0, 0];

impl Rgb8Image {
    fn new(width: usize, height: usize, fill: [u8; 3]) -> Self {
        let mut data = Vec::with_capacity(3 * width * height);
        for _ in 0..width * height {
            data.extend_from_slice(&fill);
        }
        Rgb8Image {
            width,
            height,
            data,
        }
    }

    /// Colour of pixel (x, y).
    pub fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        let i = 3 * (y * self.width + x);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// Set pixel (x, y); coordinates outside are ignored.
    fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.width && (y as usize) < self.height {
            let i = 3 * (y as usize * self.width + x as usize);
            self.data[i..i + 3].copy_from_slice(&c);
        }
    }

    fn fill_rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: [u8; 3]) {
        for yy in y..y + h {
            for xx in x..x + w {
                self.set(xx, yy, c);
            }
        }
    }

    /// Encode as an 8-bit RGB PNG in memory.
    pub fn encode_png(&self) -> std::result::Result<Vec<u8>, ::image::ImageError> {
        let mut bytes = Vec::new();
        PngEncoder::new(&mut bytes).write_image(
            &self.data,
            self.width as u32,
            self.height as u32,
            ExtendedColorType::Rgb8,
        )?;
        Ok(bytes)
    }

    fn write_png(&self, path: &str) -> Result<()> {
        let bytes = self.encode_png().map_err(|e| encode_error(path, e))?;
        write_file(path, &bytes)
    }
}

/// Cap height and descender depth \[px\] at text scale 1 (see `io/text.rs`).
const GLYPH_H: i64 = super::text::CAP_HEIGHT;
const DESCENT: i64 = super::text::DESCENT;

/// Width \[px\] of `text` drawn at integer scale `s`.
fn text_width(text: &str, s: i64) -> i64 {
    super::text::text_width(text, s)
}

/// Draw `text` in colour `c` at integer scale `s`, its capitals from row `y`
/// down to the baseline `y + 7 s`, its left edge at `x` (plotters, embedded font).
fn draw_text(img: &mut Rgb8Image, x: i64, y: i64, text: &str, s: i64, c: [u8; 3]) {
    let size = (img.width, img.height);
    super::text::draw_text(&mut img.data, size, (x, y), text, s, c);
}

/// Text in `c` with a one-font-pixel outline in `halo`, readable on any background.
fn draw_text_halo(
    img: &mut Rgb8Image,
    x: i64,
    y: i64,
    text: &str,
    s: i64,
    c: [u8; 3],
    halo: [u8; 3],
) {
    for (dx, dy) in [
        (-1, -1),
        (0, -1),
        (1, -1),
        (-1, 0),
        (1, 0),
        (-1, 1),
        (0, 1),
        (1, 1),
    ] {
        draw_text(img, x + dx * s, y + dy * s, text, s, halo);
    }
    draw_text(img, x, y, text, s, c);
}

// ---------------------------------------------------------------------------
// Scale bar

/// Unit text on the scale bar.
const UNIT_LABEL: &str = "cd/m2";

/// A vertical colour strip from `top` (max) to `bottom` (min) with ticks.
struct ScaleBar {
    /// Text scale.
    s: i64,
    top: i64,
    bottom: i64,
    /// (y of the tick, label), bottom to top.
    ticks: Vec<(i64, String)>,
}

impl ScaleBar {
    fn pad(&self) -> i64 {
        6 * self.s
    }
    fn strip_w(&self) -> i64 {
        10 * self.s
    }
    fn tick_len(&self) -> i64 {
        3 * self.s
    }

    /// Lay out a bar whose strip spans rows `top..=bottom`.
    fn new(scale: ColourScale, s: i64, top: i64, bottom: i64) -> Self {
        let span = (bottom - top).max(1);
        let gap = (GLYPH_H + 3) * s;
        let y_of = |v: f64| bottom - (scale.fraction(v) * span as f64).round() as i64;
        let mut ticks: Vec<(i64, String)> = Vec::new();
        let values = scale.ticks((span / (2 * gap)).clamp(2, 8) as usize);
        // Labels with the digits that tell neighbouring ticks apart.
        let res = values
            .windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(f64::INFINITY, f64::min);
        for v in values {
            let y = y_of(v);
            if ticks.last().is_none_or(|&(py, _)| py - y >= gap) {
                ticks.push((y, label_to(v, res)));
            }
        }
        ScaleBar {
            s,
            top,
            bottom,
            ticks,
        }
    }

    /// Width \[px\] of the bar including its padding on both sides.
    fn width(&self) -> i64 {
        let s = self.s;
        let labels = self
            .ticks
            .iter()
            .map(|(_, t)| text_width(t, s))
            .max()
            .unwrap_or(0);
        let strip_part = self.strip_w() + self.tick_len() + 2 * s + labels;
        self.pad() + strip_part.max(text_width(UNIT_LABEL, s)) + self.pad()
    }

    /// Draw at left edge `x0`; the unit label sits above the strip.
    fn draw(&self, img: &mut Rgb8Image, x0: i64) {
        let s = self.s;
        let x = x0 + self.pad();
        let span = (self.bottom - self.top).max(1);
        draw_text(img, x, self.top - (GLYPH_H + 4) * s, UNIT_LABEL, s, INK);
        for y in self.top..=self.bottom {
            let t = (self.bottom - y) as f64 / span as f64;
            img.fill_rect(x, y, self.strip_w(), 1, colour_map(t));
        }
        // Frame.
        let (w, h) = (self.strip_w(), self.bottom - self.top + 1);
        img.fill_rect(x - 1, self.top - 1, w + 2, 1, INK);
        img.fill_rect(x - 1, self.bottom + 1, w + 2, 1, INK);
        img.fill_rect(x - 1, self.top - 1, 1, h + 2, INK);
        img.fill_rect(x + w, self.top - 1, 1, h + 2, INK);
        for (y, label) in &self.ticks {
            img.fill_rect(x + w, *y, self.tick_len(), s.max(1), INK);
            let tx = x + w + self.tick_len() + 2 * s;
            draw_text(img, tx, y - (GLYPH_H * s) / 2, label, s, INK);
        }
    }
}

// ---------------------------------------------------------------------------
// False-colour image

/// Images shorter than this \[px\] are enlarged by an integer factor (each
/// pixel a block) so that the scale bar has room for its labels.
pub const FALSE_COLOUR_MIN_HEIGHT: usize = 256;

/// A rendered false-colour image: the luminance pixels as `zoom x zoom`
/// blocks at the top left (pixel (x, y) covers columns `x zoom ..`, rows
/// `y zoom ..`), the scale bar to their right.
#[derive(Clone, Debug, PartialEq)]
pub struct FalseColourPlot {
    /// The picture.
    pub image: Rgb8Image,
    /// Integer enlargement of the luminance pixels.
    pub zoom: usize,
}

/// Render `img` in false colour on `scale` with a labelled scale bar (colour
/// strip, ticks, numbers, "cd/m2") on the right. Images under
/// [`FALSE_COLOUR_MIN_HEIGHT`] rows are enlarged by an integer factor (the
/// smallest reaching it, but keeping the width within 2048 px when possible).
pub fn render_false_colour(img: &LuminanceImage, scale: ColourScale) -> Result<FalseColourPlot> {
    let l = img.checked_values()?;
    scale.validate()?;
    let (w, h) = (img.width, img.height);
    let mut zoom = FALSE_COLOUR_MIN_HEIGHT.div_ceil(h).max(1);
    zoom = zoom.min((2048 / w).max(1));
    let (zw, zh) = ((w * zoom) as i64, (h * zoom) as i64);
    let canvas_h = zh.max(FALSE_COLOUR_MIN_HEIGHT as i64);
    let s = (canvas_h / 128).clamp(1, 4);
    let top = (GLYPH_H + 4) * s + 6 * s;
    let bar = ScaleBar::new(scale, s, top, canvas_h - 1 - 6 * s);
    let mut out = Rgb8Image::new((zw + bar.width()) as usize, canvas_h as usize, WHITE);
    for y in 0..h {
        for x in 0..w {
            let c = scale.colour(l[y * w + x]);
            let z = zoom as i64;
            out.fill_rect(x as i64 * z, y as i64 * z, z, z, c);
        }
    }
    bar.draw(&mut out, zw);
    Ok(FalseColourPlot { image: out, zoom })
}

/// Write `img` in false colour on `scale` as an 8-bit RGB PNG with a
/// labelled scale bar (see [`render_false_colour`]). Colour map: viridis
/// ([`colour_map`]); `scale.min` gets the first colour, `scale.max` the last.
pub fn write_false_colour_png(img: &LuminanceImage, path: &str, scale: ColourScale) -> Result<()> {
    render_false_colour(img, scale)?.image.write_png(path)
}

// ---------------------------------------------------------------------------
// Polar plot

/// Radius \[px\] of the disc in polar plots.
pub const POLAR_RADIUS: usize = 180;

/// A rendered polar plot and where its disc lies.
#[derive(Clone, Debug, PartialEq)]
pub struct PolarPlot {
    /// The picture.
    pub image: Rgb8Image,
    /// Centre of the disc \[px\], (x right, y down), in pixel-edge coordinates.
    pub centre: (f64, f64),
    /// Radius of the disc \[px\] (theta = pi/2 at the rim).
    pub radius: f64,
}

impl PolarPlot {
    /// The pixel (column, row) showing direction `theta` \[rad\] (0 at the
    /// centre, pi/2 at the rim), `phi` \[rad\] (0 to the right, counterclockwise).
    pub fn pixel_at(&self, theta: f64, phi: f64) -> (usize, usize) {
        let r = theta / FRAC_PI_2 * self.radius;
        let x = self.centre.0 + r * phi.cos();
        let y = self.centre.1 - r * phi.sin();
        (x.floor() as usize, y.floor() as usize)
    }
}

/// L on a tensor grid of (theta, phi) nodes, bilinear, periodic in phi.
#[derive(Debug)]
struct PolarGrid {
    thetas: Vec<f64>,
    phis: Vec<f64>,
    /// `l[i * phis.len() + j]` at (`thetas[i]`, `phis[j]`).
    l: Vec<f64>,
}

/// Tolerance \[rad\] when matching sample angles to grid nodes.
const ANGLE_TOL: f64 = 1e-9;

/// Sorted distinct values of `v`, merging values within [`ANGLE_TOL`].
fn distinct(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::new();
    for x in v {
        if out.last().is_none_or(|&p| x - p > ANGLE_TOL) {
            out.push(x);
        }
    }
    out
}

fn node(nodes: &[f64], x: f64) -> Option<usize> {
    let i = nodes.partition_point(|&n| n < x - ANGLE_TOL);
    (i < nodes.len() && (nodes[i] - x).abs() <= ANGLE_TOL).then_some(i)
}

impl PolarGrid {
    /// Detect the grid of `(theta, phi, L)` samples: every combination of
    /// the distinct thetas and phis (phi taken modulo 2 pi) exactly once.
    fn new(samples: &[(f64, f64, f64)]) -> Result<Self> {
        if samples.is_empty() {
            return invalid("no samples for the polar plot");
        }
        let deg = |x: f64| x.to_degrees();
        let mut pts = Vec::with_capacity(samples.len());
        for (k, &(t, p, _)) in samples.iter().enumerate() {
            if !(t.is_finite() && p.is_finite()) {
                return invalid(format!("sample {k}: direction ({t}, {p}) is not finite"));
            }
            if !(-ANGLE_TOL..=FRAC_PI_2 + ANGLE_TOL).contains(&t) {
                return invalid(format!(
                    "sample {k}: theta = {:.6} deg is outside the hemisphere [0, 90] deg",
                    deg(t)
                ));
            }
            let mut p = p.rem_euclid(TAU);
            if p > TAU - ANGLE_TOL {
                p = 0.0;
            }
            pts.push((t.clamp(0.0, FRAC_PI_2), p));
        }
        let ls: Vec<f64> = samples.iter().map(|s| s.2).collect();
        let ls = clean_values(&ls, |k| {
            format!(
                "sample {k} (theta = {:.4} deg, phi = {:.4} deg)",
                deg(samples[k].0),
                deg(samples[k].1)
            )
        })?;
        let thetas = distinct(pts.iter().map(|p| p.0).collect());
        let phis = distinct(pts.iter().map(|p| p.1).collect());
        let (nt, np) = (thetas.len(), phis.len());
        let mut grid: Vec<Option<f64>> = vec![None; nt * np];
        for (k, (&(t, p), &l)) in pts.iter().zip(&ls).enumerate() {
            let (i, j) = (node(&thetas, t), node(&phis, p));
            let (Some(i), Some(j)) = (i, j) else {
                unreachable!("every sample angle is a node")
            };
            if grid[i * np + j].replace(l).is_some() {
                return invalid(format!(
                    "sample {k}: second sample at theta = {:.4} deg, phi = {:.4} deg (phi is taken modulo 360 deg)",
                    deg(t),
                    deg(p)
                ));
            }
        }
        if let Some(m) = grid.iter().position(Option::is_none) {
            return invalid(format!(
                "the samples do not form a full theta x phi grid ({nt} thetas x {np} phis needs {} samples, got {}): \
                 none at theta = {:.4} deg, phi = {:.4} deg",
                nt * np,
                samples.len(),
                deg(thetas[m / np]),
                deg(phis[m % np])
            ));
        }
        Ok(PolarGrid {
            thetas,
            phis,
            l: grid.into_iter().map(|v| v.unwrap_or(0.0)).collect(),
        })
    }

    /// Bilinear L at (theta, phi): clamped beyond the first and last theta,
    /// periodic in phi (between the last and the first node across 2 pi).
    fn eval(&self, theta: f64, phi: f64) -> f64 {
        let (ts, ps) = (&self.thetas, &self.phis);
        let (i0, i1, f) = if theta <= ts[0] {
            (0, 0, 0.0)
        } else if theta >= ts[ts.len() - 1] {
            (ts.len() - 1, ts.len() - 1, 0.0)
        } else {
            let i = ts.partition_point(|&t| t <= theta) - 1;
            (i, i + 1, (theta - ts[i]) / (ts[i + 1] - ts[i]))
        };
        let np = ps.len();
        let (j0, j1, g) = if np == 1 {
            (0, 0, 0.0)
        } else {
            let phi = phi.rem_euclid(TAU);
            if phi < ps[0] || phi >= ps[np - 1] {
                let span = ps[0] + TAU - ps[np - 1];
                (np - 1, 0, (phi - ps[np - 1]).rem_euclid(TAU) / span)
            } else {
                let j = ps.partition_point(|&p| p <= phi) - 1;
                (j, j + 1, (phi - ps[j]) / (ps[j + 1] - ps[j]))
            }
        };
        let v = |i: usize, j: usize| self.l[i * np + j];
        (1.0 - f) * ((1.0 - g) * v(i0, j0) + g * v(i0, j1))
            + f * ((1.0 - g) * v(i1, j0) + g * v(i1, j1))
    }
}

fn blend(c: [u8; 3], d: [u8; 3], a: f64) -> [u8; 3] {
    std::array::from_fn(|k| (c[k] as f64 * (1.0 - a) + d[k] as f64 * a).round() as u8)
}

/// Render a polar plot of L(theta, phi) over a hemisphere (see [`write_polar_png`]).
pub fn render_polar(
    samples: &[(f64, f64, f64)],
    scale: ColourScale,
    title: &str,
) -> Result<PolarPlot> {
    scale.validate()?;
    let grid = PolarGrid::new(samples)?;
    let s: i64 = 2;
    let pad = 10;
    let th = GLYPH_H * s;
    let r = POLAR_RADIUS as i64;
    let captions = [
        "radius: θ (rings 30°, 60°, 90°)",
        "angle: φ (0° right, counterclockwise)",
    ];

    let disc_top = pad + th + pad + th + 6;
    let left = pad + text_width("180°", s) + 8;
    let (cx, cy) = (left + r, disc_top + r);
    let phi0_x = cx + r + 8;
    let bar_x = phi0_x + text_width("0°", s) + pad;
    let bar = ScaleBar::new(scale, s, disc_top + th + 4 * s, cy + r);
    let caption_y = cy + r + 6 + th + pad;
    let line = (GLYPH_H + DESCENT + 2) * s;
    let height = caption_y + 2 * line + pad;
    let mut width = bar_x + bar.width();
    for t in captions.iter().chain([&title]) {
        width = width.max(text_width(t, s) + 2 * pad);
    }
    let mut img = Rgb8Image::new(width as usize, height as usize, WHITE);

    // Disc, rings at 30 and 60 deg, spokes (the phi ticks) at 0/90/180/270
    // deg, black rim.
    let rf = r as f64;
    let (cxf, cyf) = (cx as f64, cy as f64);
    for py in cy - r - 2..=cy + r + 2 {
        for px in cx - r - 2..=cx + r + 2 {
            let (dx, dy) = (px as f64 + 0.5 - cxf, cyf - (py as f64 + 0.5));
            let rho = dx.hypot(dy);
            if rho > rf + 1.5 {
                continue;
            }
            if rho >= rf {
                img.set(px, py, INK);
                continue;
            }
            let theta = rho / rf * FRAC_PI_2;
            let phi = dy.atan2(dx);
            let mut c = scale.colour(grid.eval(theta, phi));
            if [1.0 / 3.0, 2.0 / 3.0]
                .iter()
                .any(|&q| (rho - q * rf).abs() < 0.75)
            {
                c = blend(c, WHITE, 0.6);
            } else if px == cx || py == cy {
                c = blend(c, WHITE, 0.35);
            }
            img.set(px, py, c);
        }
    }
    // phi labels at the ends of the spokes.
    draw_text(&mut img, phi0_x, cy - th / 2, "0°", s, INK);
    draw_text(
        &mut img,
        cx - text_width("90°", s) / 2,
        disc_top - 6 - th,
        "90°",
        s,
        INK,
    );
    draw_text(
        &mut img,
        cx - r - 8 - text_width("180°", s),
        cy - th / 2,
        "180°",
        s,
        INK,
    );
    draw_text(
        &mut img,
        cx - text_width("270°", s) / 2,
        cy + r + 7,
        "270°",
        s,
        INK,
    );
    // theta labels along the lower-right diagonal (phi = 315 deg).
    let diag = std::f64::consts::FRAC_1_SQRT_2;
    for (q, label) in [(1.0 / 3.0, "30°"), (2.0 / 3.0, "60°")] {
        let d = (q * rf * diag).round() as i64;
        draw_text_halo(&mut img, cx + d + 2 * s, cy + d + s, label, s, INK, WHITE);
    }
    let d = ((rf + 3.0) * diag).round() as i64;
    draw_text(&mut img, cx + d, cy + d, "90°", s, INK);

    draw_text(
        &mut img,
        (width - text_width(title, s)) / 2,
        pad,
        title,
        s,
        INK,
    );
    for (k, c) in captions.iter().enumerate() {
        draw_text(
            &mut img,
            (width - text_width(c, s)) / 2,
            caption_y + k as i64 * line,
            c,
            s,
            INK,
        );
    }
    bar.draw(&mut img, bar_x);
    Ok(PolarPlot {
        image: img,
        centre: (cxf, cyf),
        radius: rf,
    })
}

/// Write a polar plot of L(theta, phi) over a hemisphere as an 8-bit RGB PNG.
///
/// `samples` are `(theta [rad] in [0, pi/2], phi [rad], L [cd/m^2])` on a
/// grid: every combination of the distinct thetas and the distinct phis
/// (phi modulo 2 pi) exactly once, any spacing (a regular grid, with or
/// without the pole and the rim, is the usual case). The disc has radius
/// proportional to theta (0 at the centre, pi/2 at the rim) and angle phi
/// (0 to the right, counterclockwise, so 90 deg is up). Each pixel shows L
/// interpolated bilinearly between the grid nodes (periodic in phi, held
/// constant beyond the first and last theta), coloured on `scale` as in
/// [`write_false_colour_png`], with rings at theta = 30, 60, 90 deg, phi ticks
/// at 0, 90, 180, 270 deg, `title` above and the labelled scale bar on the
/// right. Errors: no samples, a theta outside [0, 90] deg, an incomplete or
/// repeated grid node, a non-finite or negative L, a bad scale.
pub fn write_polar_png(
    path: &str,
    samples: &[(f64, f64, f64)],
    scale: ColourScale,
    title: &str,
) -> Result<()> {
    render_polar(samples, scale, title)?.image.write_png(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative luminance of an 8-bit sRGB colour (decoded, Rec. 709 weights).
    fn lightness(c: [u8; 3]) -> f64 {
        let lin = |v: u8| {
            let v = v as f64 / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        0.2126 * lin(c[0]) + 0.7152 * lin(c[1]) + 0.0722 * lin(c[2])
    }

    #[test]
    fn colour_map_lightness_increases_from_first_to_last_entry() {
        assert_eq!(colour_map(0.0), VIRIDIS[0]);
        assert_eq!(colour_map(1.0), VIRIDIS[16]);
        assert_eq!(colour_map(-1.0), VIRIDIS[0]);
        assert_eq!(colour_map(f64::NAN), VIRIDIS[0]);
        let ys: Vec<f64> = (0..=256)
            .map(|k| lightness(colour_map(k as f64 / 256.0)))
            .collect();
        // 8-bit rounding of a channel that falls while others rise can cost
        // a hair between neighbouring steps; over 1/16 it always gains.
        for w in ys.windows(2) {
            assert!(w[1] >= w[0] * 0.99, "lightness must not decrease: {w:?}");
        }
        for w in ys.windows(17) {
            assert!(w[16] > w[0], "lightness must increase over 1/16: {w:?}");
        }
        for w in VIRIDIS.windows(2) {
            assert!(lightness(w[1]) > lightness(w[0]));
        }
        assert!(ys[256] > 10.0 * ys[0]);
    }

    #[test]
    fn srgb_curve_is_the_piecewise_standard() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        assert!((srgb_encode(0.002) - 12.92 * 0.002).abs() < 1e-15);
        // Continuous at the knee.
        let k: f64 = 0.003_130_8;
        assert!((12.92 * k - (1.055 * k.powf(1.0 / 2.4) - 0.055)).abs() < 1e-6);
        assert_eq!(display_byte(0.5, 1.0), 188);
        assert_eq!(display_byte(0.25, 2.0), 188);
        assert_eq!(display_byte(3.0, 1.0), 255);
        assert_eq!(display_byte(0.0, 1.0), 0);
    }

    #[test]
    fn auto_exposure_maps_the_99th_percentile_to_white() {
        let mut l: Vec<f64> = (1..=100).map(|k| k as f64).collect();
        l[99] = 1e6; // one hot pixel out of 100 does not set the exposure
        let img = LuminanceImage::new(10, 10, l).unwrap();
        let k = exposure_multiplier(&img, Exposure::Auto).unwrap();
        assert!((k - 1.0 / 99.0).abs() < 1e-15);
        let black = LuminanceImage::new(2, 1, vec![0.0, 0.0]).unwrap();
        assert_eq!(exposure_multiplier(&black, Exposure::Auto).unwrap(), 1.0);
        assert!(exposure_multiplier(&black, Exposure::Fixed(0.0)).is_err());
        assert!(exposure_multiplier(&black, Exposure::Fixed(f64::NAN)).is_err());
    }

    #[test]
    fn construction_cleans_round_off_and_rejects_bad_values() {
        let img = LuminanceImage::new(3, 1, vec![1.0, -1e-14, -0.0]).unwrap();
        assert_eq!(img.l, vec![1.0, 0.0, 0.0]);
        assert!(img.l[2].is_sign_positive());
        let e = LuminanceImage::new(2, 1, vec![1.0, -1e-3])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("pixel (x=1, y=0)") && e.contains("negative"),
            "{e}"
        );
        let e = LuminanceImage::new(2, 1, vec![f64::NAN, 1.0])
            .unwrap_err()
            .to_string();
        assert!(e.contains("finite"), "{e}");
        assert!(LuminanceImage::new(2, 1, vec![f64::INFINITY, 1.0]).is_err());
        assert!(LuminanceImage::new(2, 2, vec![1.0; 3]).is_err());
        assert!(LuminanceImage::new(0, 0, vec![]).is_err());
        // All tiny negatives with nothing positive: no round-off excuse.
        assert!(LuminanceImage::new(1, 1, vec![-1e-30]).is_err());
    }

    #[test]
    fn labels_tell_apart_marks_a_step_apart() {
        // Isolux levels 0.5 lx apart near 200 lx; a bar from 198.5 to 199.9.
        assert_eq!(label_to(199.5, 0.5), "199.5");
        assert_eq!(label_to(199.0, 0.5), "199");
        assert_eq!(label_to(200.0, 0.25), "200");
        assert_eq!(label_to(199.75, 0.25), "199.75");
        let bar: Vec<String> = (0..8)
            .map(|k| label_to(198.6 + 0.2 * k as f64, 1.43 / 50.0))
            .collect();
        assert_eq!(
            bar,
            [
                "198.6", "198.8", "199", "199.2", "199.4", "199.6", "199.8", "200"
            ]
        );
        // Daylight near 1e5 lx, levels 100 lx apart; small values as before.
        assert_eq!(label_to(100_500.0, 100.0), "1.005e5");
        assert_eq!(label_to(99_900.0, 100.0), "99900");
        assert_eq!(label_to(0.3, 0.1), "0.3");
        assert_eq!(label_to(1234.0, 200.0), "1234");
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(0.0), "0");
        assert_eq!(tick_label(0.30000000000000004), "0.3");
        assert_eq!(tick_label(1.0), "1");
        assert_eq!(tick_label(1000.0), "1000");
        assert_eq!(tick_label(0.001), "0.001");
        assert_eq!(tick_label(2.5e-7), "2.5e-7");
        assert_eq!(tick_label(1e5), "1e5");
        assert_eq!(tick_label(123.456), "123");
        assert_eq!(tick_label(-0.05), "-0.05");
    }

    #[test]
    fn ticks_fall_inside_the_scale() {
        let lin = ColourScale {
            min: 0.0,
            max: 1.0,
            log: false,
        };
        assert_eq!(
            lin.ticks(5),
            vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]
        );
        let log = ColourScale {
            min: 0.05,
            max: 50.0,
            log: true,
        };
        assert_eq!(log.ticks(6), vec![0.1, 1.0, 10.0]);
        let narrow = ColourScale {
            min: 3.0,
            max: 7.0,
            log: true,
        };
        // No decade and only one 2/5 multiple (5) inside: the two ends instead.
        assert_eq!(narrow.ticks(6), vec![3.0, 7.0]);
        for sc in [
            lin,
            log,
            narrow,
            ColourScale {
                min: 1e-9,
                max: 1e9,
                log: true,
            },
        ] {
            for t in sc.ticks(4) {
                assert!(
                    t >= sc.min * (1.0 - 1e-9) && t <= sc.max * (1.0 + 1e-9),
                    "{sc:?}: {t}"
                );
            }
        }
    }

    #[test]
    fn scale_bar_labels_put_ink_beside_the_strip() {
        let scale = ColourScale {
            min: 0.01,
            max: 100.0,
            log: true,
        };
        let bar = ScaleBar::new(scale, 2, 40, 250);
        assert!(bar.ticks.len() >= 3, "{:?}", bar.ticks);
        let labels: Vec<&str> = bar.ticks.iter().map(|t| t.1.as_str()).collect();
        assert!(
            labels.contains(&"1") && labels.contains(&"100"),
            "{labels:?}"
        );
        let mut img = Rgb8Image::new(bar.width() as usize, 260, WHITE);
        bar.draw(&mut img, 0);
        let label_x0 = (bar.pad() + bar.strip_w() + bar.tick_len() + 2) as usize;
        for (y, label) in &bar.ticks {
            let y0 = (*y - 7).max(0) as usize;
            let ink = (y0..y0 + 14)
                .flat_map(|yy| (label_x0..img.width).map(move |x| (x, yy)))
                .filter(|&(x, yy)| img.pixel(x, yy).iter().all(|&v| v < 60))
                .count();
            assert!(ink > 10, "label {label} at y={y} has {ink} ink pixels");
        }
        // Strip ends: max colour at the top, min at the bottom.
        let xs = (bar.pad() + 2) as usize;
        assert_eq!(img.pixel(xs, 40), colour_map(1.0));
        assert_eq!(img.pixel(xs, 250), colour_map(0.0));
    }

    #[test]
    fn polar_grid_interpolates_and_wraps_in_phi() {
        let samples: Vec<(f64, f64, f64)> = [0.0, 45.0, 90.0]
            .iter()
            .flat_map(|&t: &f64| {
                [0.0, 90.0, 180.0, 270.0]
                    .map(move |p: f64| (t.to_radians(), p.to_radians(), t + p / 90.0))
            })
            .collect();
        let g = PolarGrid::new(&samples).unwrap();
        assert_eq!((g.thetas.len(), g.phis.len()), (3, 4));
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        assert!(close(g.eval(45f64.to_radians(), 90f64.to_radians()), 46.0));
        assert!(close(
            g.eval(22.5f64.to_radians(), 45f64.to_radians()),
            23.0
        ));
        // Between 270 deg (value t + 3) and 360 = 0 deg (value t).
        assert!(close(g.eval(0.0, 315f64.to_radians()), 1.5));
        assert!(close(g.eval(0.0, -45f64.to_radians()), 1.5));
        let mut missing = samples.clone();
        missing.pop();
        assert!(
            PolarGrid::new(&missing)
                .unwrap_err()
                .to_string()
                .contains("full theta x phi grid")
        );
        let mut dup = samples.clone();
        dup[0].1 = TAU; // 360 deg = 0 deg, already there
        dup.pop();
        assert!(PolarGrid::new(&dup).is_err());
        let mut low = samples;
        low[0].0 = 2.0;
        assert!(
            PolarGrid::new(&low)
                .unwrap_err()
                .to_string()
                .contains("hemisphere")
        );
    }

    #[test]
    fn hdr_mantissa_rounds_to_nearest() {
        // 1 + 1.9/128 is mantissa 129.9 (exponent 2^1): truncation would give
        // 129, rounding to nearest gives 130.
        let img = LuminanceImage::new(1, 1, vec![1.0 + 1.9 / 128.0]).unwrap();
        let bytes = encode_hdr(&img).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.starts_with("#?RADIANCE\n# lumest:"), "{text}");
        assert!(text.contains("FORMAT=32-bit_rle_rgbe"));
        let px = &bytes[bytes.len() - 4..];
        assert_eq!(px, &[130, 130, 130, 129]);
    }
}
