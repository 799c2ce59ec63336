//! Environment maps: a Radiance RGBE `.hdr` or an OpenEXR `.exr` file (through the `image`
//! crate) read as per-pixel luminance. Formats only: the light's mapping
//! and scale are applied in [`crate::light::environment`].
//!
//! A Radiance header's `EXPOSURE=` and `COLORCORR=` lines are applied
//! (the `image` crate reads but does not apply them): by Radiance's
//! convention the stored values are the true ones times every `EXPOSURE`
//! and, per channel, every `COLORCORR` factor found in the header, so the
//! true value is the stored one divided by their products (Ward, "The
//! RADIANCE Picture File Format", and Radiance's `getheader(1)`/`pfilt(1)`).
//!
//! Only these two float formats are read: an 8- or 16-bit image (PNG,
//! JPEG, ...) holds display values, gamma-encoded and clipped, not
//! luminance, and is refused rather than read as if it were.
//!
//! An RGBE pixel of mantissa byte `m` and exponent byte `e` decodes to
//! `m 2^(e - 136)`, as the `image` crate and Walter's widely used
//! `rgbe.c` read it; Radiance's own `colr_color` adds half a step,
//! `(m + 0.5) 2^(e - 136)`, the middle of the interval its truncating
//! writer maps to `m`. A map written by Radiance's tools therefore reads
//! low here by half a step, `0.5 / m` relative: 0.2-0.4 % for the largest
//! channel (`m` 128-255). Not corrected: maps from writers that round to
//! nearest (lumest's own, the `image` crate's) would then read high.

use ::image::codecs::hdr::HdrDecoder;
use ::image::{DynamicImage, ImageFormat};
use std::path::Path;

/// A map's pixels as luminance values, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct LuminanceMap {
    /// Width \[pixels\].
    pub width: usize,
    /// Height \[pixels\].
    pub height: usize,
    /// `Y` of each pixel, row-major (the pixel value; see [`luminance_of`]),
    /// after the header's exposure and colour correction.
    pub y: Vec<f64>,
    /// The product of a Radiance header's `EXPOSURE=` values (1 without
    /// any): the stored values were divided by it.
    pub exposure: f64,
    /// The products of a Radiance header's `COLORCORR=` values per channel
    /// (R, G, B; 1 without any): the stored channels were divided by them.
    pub colour_correction: [f64; 3],
}

impl LuminanceMap {
    /// A note of the header's factors applied, empty when there are none.
    pub fn header_note(&self) -> String {
        let mut parts = Vec::new();
        if self.exposure != 1.0 {
            parts.push(format!("EXPOSURE {} applied", self.exposure));
        }
        if self.colour_correction != [1.0; 3] {
            let [r, g, b] = self.colour_correction;
            parts.push(format!("COLORCORR {r} {g} {b} applied"));
        }
        if parts.is_empty() {
            String::new()
        } else {
            format!("{} (stored values divided by them)", parts.join(", "))
        }
    }
}

/// The products of the `EXPOSURE=` values and, per channel, of the
/// `COLORCORR=` values of a Radiance header's `(key, value)` lines, in
/// `f64` from the header's text; each must be finite and positive.
pub fn radiance_header_factors(lines: &[(String, String)]) -> Result<(f64, [f64; 3]), String> {
    let mut exposure = 1.0;
    let mut corr = [1.0; 3];
    let positive = |key: &str, v: &str| -> Result<f64, String> {
        match v.trim().parse::<f64>() {
            Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
            _ => Err(format!(
                "header line `{key}={v}`: the factor must be a finite number > 0"
            )),
        }
    };
    for (key, value) in lines {
        match key.as_str() {
            "EXPOSURE" => exposure *= positive(key, value)?,
            "COLORCORR" => {
                let parts: Vec<&str> = value.split_whitespace().collect();
                if parts.len() != 3 {
                    return Err(format!(
                        "header line `{key}={value}`: needs three factors (R G B)"
                    ));
                }
                for (c, p) in corr.iter_mut().zip(parts) {
                    *c *= positive(key, p)?;
                }
            }
            _ => {}
        }
    }
    if !(exposure.is_finite() && exposure > 0.0 && corr.iter().all(|c| c.is_finite() && *c > 0.0)) {
        return Err("the header's EXPOSURE or COLORCORR factors multiply to 0 or infinity".into());
    }
    Ok((exposure, corr))
}

/// The luminance-weighted value of an RGB pixel: `Y = 0.2126 R + 0.7152 G
/// + 0.0722 B` (ITU-R BT.709, the sRGB primaries), and exactly the value of
/// a grey pixel (`R = G = B`).
#[inline]
pub fn luminance_of(r: f64, g: f64, b: f64) -> f64 {
    if r == g && g == b {
        r
    } else {
        0.2126 * r + 0.7152 * g + 0.0722 * b
    }
}

/// Read an environment map (a Radiance `.hdr` or an OpenEXR `.exr`; any
/// other image is refused, module docs) as luminance values. Errors name the problem; the caller adds the
/// file and field.
pub fn read_luminance_map(path: &Path) -> Result<LuminanceMap, String> {
    let reader = ::image::ImageReader::open(path)
        .map_err(|e| format!("cannot open `{}`: {e}", path.display()))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let decode_error = |e: ::image::ImageError| format!("cannot decode `{}`: {e}", path.display());
    match reader.format() {
        Some(ImageFormat::Hdr | ImageFormat::OpenExr) => {}
        other => {
            let what = other.map_or(
                "not a Radiance .hdr or OpenEXR .exr file".to_string(),
                |f| format!("a {f:?} image"),
            );
            return Err(format!(
                "`{}` is {what}: an environment map must be a float Radiance .hdr or OpenEXR \
                 .exr file (8- and 16-bit images hold gamma-encoded display values, not \
                 luminance)",
                path.display()
            ));
        }
    }
    let (img, exposure, corr) = if reader.format() == Some(ImageFormat::Hdr) {
        // Decode through the Radiance decoder itself to read its header.
        let file = std::fs::File::open(path)
            .map_err(|e| format!("cannot open `{}`: {e}", path.display()))?;
        let decoder = HdrDecoder::new(std::io::BufReader::new(file)).map_err(decode_error)?;
        let (exposure, corr) = radiance_header_factors(&decoder.metadata().custom_attributes)
            .map_err(|m| format!("`{}`: {m}", path.display()))?;
        let img = DynamicImage::from_decoder(decoder).map_err(decode_error)?;
        (img.to_rgb32f(), exposure, corr)
    } else {
        (
            reader.decode().map_err(decode_error)?.to_rgb32f(),
            1.0,
            [1.0; 3],
        )
    };
    let div = corr.map(|c| exposure * c);
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 {
        return Err(format!("`{}` is empty", path.display()));
    }
    let mut y = Vec::with_capacity(w * h);
    for (k, p) in img.pixels().enumerate() {
        let v = luminance_of(
            p[0] as f64 / div[0],
            p[1] as f64 / div[1],
            p[2] as f64 / div[2],
        );
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "`{}`: pixel (x={}, y={}) has luminance {v}: values must be finite and >= 0",
                path.display(),
                k % w,
                k / w
            ));
        }
        y.push(v);
    }
    Ok(LuminanceMap {
        width: w,
        height: h,
        y,
        exposure,
        colour_correction: corr,
    })
}
