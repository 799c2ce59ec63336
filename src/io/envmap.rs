//! Environment maps: a Radiance RGBE `.hdr` or an OpenEXR `.exr` file (through the `image`
//! crate) read as per-pixel luminance. Formats only: the light's mapping
//! and scale are applied in [`crate::light::environment`].

use std::path::Path;

/// A map's pixels as luminance values, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct LuminanceMap {
    /// Width [pixels].
    pub width: usize,
    /// Height [pixels].
    pub height: usize,
    /// `Y` of each pixel, row-major (the pixel value; see [`luminance_of`]).
    pub y: Vec<f64>,
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

/// Read an environment map (`.hdr`, `.exr`; any format the `image` crate was built
/// with) as luminance values. Errors name the problem; the caller adds the
/// file and field.
pub fn read_luminance_map(path: &Path) -> Result<LuminanceMap, String> {
    let img = ::image::ImageReader::open(path)
        .map_err(|e| format!("cannot open `{}`: {e}", path.display()))?
        .with_guessed_format()
        .map_err(|e| format!("cannot read `{}`: {e}", path.display()))?
        .decode()
        .map_err(|e| format!("cannot decode `{}`: {e}", path.display()))?
        .to_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 {
        return Err(format!("`{}` is empty", path.display()));
    }
    let mut y = Vec::with_capacity(w * h);
    for (k, p) in img.pixels().enumerate() {
        let v = luminance_of(p[0] as f64, p[1] as f64, p[2] as f64);
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
    })
}
