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
//! Every one of the eight orientations of a Radiance resolution line is
//! read (`-Y H +X W`, the standard one, and the flipped and transposed
//! ones such as `+Y H -X W` or `+X W -Y H`: the first axis is the one the
//! scanlines advance along, its sign the direction, see [`Orientation`]);
//! the `image` crate decodes the standard one only, so the scanlines are
//! decoded as if standard and put in place here.
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
    let (img, exposure, corr, orientation) = if reader.format() == Some(ImageFormat::Hdr) {
        // Decode through the Radiance decoder itself to read its header,
        // with the resolution line made standard (module docs).
        let mut bytes =
            std::fs::read(path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
        let orientation = Orientation::standardise(&mut bytes)
            .map_err(|m| format!("cannot decode `{}`: {m}", path.display()))?;
        let decoder = HdrDecoder::new(std::io::Cursor::new(bytes)).map_err(decode_error)?;
        let (exposure, corr) = radiance_header_factors(&decoder.metadata().custom_attributes)
            .map_err(|m| format!("`{}`: {m}", path.display()))?;
        let img = DynamicImage::from_decoder(decoder).map_err(decode_error)?;
        (img.to_rgb32f(), exposure, corr, orientation)
    } else {
        (
            reader.decode().map_err(decode_error)?.to_rgb32f(),
            1.0,
            [1.0; 3],
            Orientation::STANDARD,
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
    let (y, w, h) = orientation.place(y, w, h);
    Ok(LuminanceMap {
        width: w,
        height: h,
        y,
        exposure,
        colour_correction: corr,
    })
}

/// The pixel order of a Radiance picture, from its resolution line: the
/// scanlines advance along the first axis named (`Y` or `X`), in the
/// direction of its sign (`-Y`: from the top down, `Y` pointing up; `+X`:
/// from the left), and the pixels of a scanline along the second. The
/// standard `-Y H +X W` is row-major from the top left.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orientation {
    /// The scanlines advance along `X` (columns), not `Y` (rows).
    pub transposed: bool,
    /// Signs of the first and second axes (`true`: `+`).
    pub ascending: [bool; 2],
}

impl Orientation {
    /// `-Y H +X W`.
    pub const STANDARD: Self = Self {
        transposed: false,
        ascending: [false, true],
    };

    /// Read the resolution line of the Radiance picture `bytes` (the line
    /// after the header's blank line) and, where it is not the standard
    /// one, rewrite it in place as `-Y n1 +X n2` (its two counts in their
    /// order, padded to the same length), so that a standard decoder reads
    /// the scanlines as they lie; returns the orientation found. An
    /// unreadable line is left to the decoder's own error.
    pub fn standardise(bytes: &mut [u8]) -> Result<Self, String> {
        let Some(blank) = bytes.windows(2).position(|w| w == b"\n\n") else {
            return Ok(Self::STANDARD);
        };
        let start = blank + 2;
        let Some(len) = bytes[start..].iter().take(256).position(|&b| b == b'\n') else {
            return Ok(Self::STANDARD);
        };
        let line = String::from_utf8_lossy(&bytes[start..start + len]).into_owned();
        let t: Vec<&str> = line.split_whitespace().collect();
        let axis = |a: &str| match a {
            "-Y" => Some(('Y', false)),
            "+Y" => Some(('Y', true)),
            "-X" => Some(('X', false)),
            "+X" => Some(('X', true)),
            _ => None,
        };
        let (Some((a1, s1)), Some((a2, s2))) = (
            t.first().and_then(|a| axis(a)),
            t.get(2).and_then(|a| axis(a)),
        ) else {
            return Ok(Self::STANDARD);
        };
        if t.len() != 4 {
            return Err(format!(
                "resolution line `{line}`: expected 4 fields (two axes, each with its count), found {}",
                t.len()
            ));
        }
        if a1 == a2 {
            return Err(format!(
                "resolution line `{line}`: names {a1} twice (it needs one X and one Y axis)"
            ));
        }
        for (axis, count) in [(a1, t[1]), (a2, t[3])] {
            if count.parse::<u32>().is_err() {
                return Err(format!(
                    "resolution line `{line}`: the {axis} count `{count}` is not a whole number of pixels"
                ));
            }
        }
        let found = Self {
            transposed: a1 == 'X',
            ascending: [s1, s2],
        };
        if found != Self::STANDARD {
            let new = format!("-Y {} +X {}", t[1], t[3]);
            // The same length: pad with spaces before the newline (the
            // decoder splits on whitespace).
            if new.len() > len {
                return Err(format!("resolution line `{line}` cannot be read"));
            }
            let padded = format!("{new:<len$}");
            bytes[start..start + len].copy_from_slice(padded.as_bytes());
        }
        Ok(found)
    }

    /// Put `y`, decoded as `n2` pixels by `n1` scanlines in file order
    /// (`w = n2`, `h = n1`), in place: row-major from the top left of the
    /// picture. Returns the values, the width and the height.
    pub fn place(self, y: Vec<f64>, w: usize, h: usize) -> (Vec<f64>, usize, usize) {
        if self == Self::STANDARD {
            return (y, w, h);
        }
        let (n1, n2) = (h, w);
        let (width, height) = if self.transposed { (n1, n2) } else { (n2, n1) };
        let mut out = vec![0.0; y.len()];
        for i in 0..n1 {
            let a1 = if self.ascending[0] { i } else { n1 - 1 - i };
            for j in 0..n2 {
                let a2 = if self.ascending[1] { j } else { n2 - 1 - j };
                // Picture coordinates, X from the left and Y from the bottom.
                let (x, yy) = if self.transposed { (a1, a2) } else { (a2, a1) };
                out[(height - 1 - yy) * width + x] = y[i * n2 + j];
            }
        }
        (out, width, height)
    }
}
