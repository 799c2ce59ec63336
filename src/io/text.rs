//! Text on 8-bit RGB rasters: plotters' `ab_glyph` rasteriser with DejaVu
//! Sans embedded in the binary (the `dejavu` crate), so nothing depends on
//! system fonts or fontconfig.
//!
//! Sizes are given as an integer scale `s`: capitals are `CAP_HEIGHT s`
//! pixels tall, the baseline lies `CAP_HEIGHT s` below the `y` a caller
//! passes and descenders reach about `DESCENT s` below it. The font size
//! (plotters' size is the ascent-to-descent height `1.164 em` of DejaVu
//! Sans) follows from its cap height `1493 / 2048 em`:
//! `size = CAP_HEIGHT s 1.164 / 0.729`. Glyphs are anti-aliased (blended
//! into the background), so text pixels are shades between background and ink.

use plotters::backend::DrawingBackend;
use plotters::prelude::{BitMapBackend, FontDesc, RGBColor, TextStyle};
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontFamily, FontStyle, register_font};
use std::sync::Once;

/// Cap height \[px\] at scale 1.
pub(crate) const CAP_HEIGHT: i64 = 7;

/// Depth of descenders below the baseline \[px\] at scale 1.
pub(crate) const DESCENT: i64 = 2;

/// Name under which the embedded font is registered with plotters.
const FAMILY: &str = "lumest-dejavu-sans";

/// DejaVu Sans metrics [font units]: ascent, descent (positive), cap height.
const ASCENT: f64 = 1901.0;
const DESCENDER: f64 = 483.0;
const CAP: f64 = 1493.0;

static REGISTER: Once = Once::new();

/// Register the embedded font with plotters, once: under this module's own
/// name and under the generic families `sans-serif`, `serif` and
/// `monospace` that plotters' charts ask for (text layout needs a font even
/// for SVG output, which names the family and leaves drawing to the viewer).
pub(crate) fn register_fonts() {
    REGISTER.call_once(|| {
        for name in [FAMILY, "sans-serif", "serif", "monospace"] {
            register_font(name, FontStyle::Normal, dejavu::sans::regular())
                .unwrap_or_else(|_| panic!("the embedded DejaVu Sans is a valid font"));
        }
    });
}

/// The font at integer scale `s`.
fn font(s: i64) -> FontDesc<'static> {
    register_fonts();
    let size = (CAP_HEIGHT * s) as f64 * (ASCENT + DESCENDER) / CAP;
    FontDesc::new(FontFamily::Name(FAMILY), size, FontStyle::Normal)
}

/// Width \[px\] of `text` at scale `s` (sum of the glyph advances).
pub(crate) fn text_width(text: &str, s: i64) -> i64 {
    if text.is_empty() {
        return 0;
    }
    font(s).box_size(text).map_or(0, |(w, _)| w as i64)
}

/// Draw `text` in colour `c` on the RGB buffer `data` (`width x height`,
/// 3 bytes per pixel, row-major) with the top of its capitals at `y` and
/// its left edge at `x`. Pixels outside the buffer are clipped.
pub(crate) fn draw_text(
    data: &mut [u8],
    (width, height): (usize, usize),
    (x, y): (i64, i64),
    text: &str,
    s: i64,
    c: [u8; 3],
) {
    let f = font(s);
    // ab_glyph puts the baseline half a font size below the anchor.
    let top = y + CAP_HEIGHT * s - (0.5 * f.get_size()).round() as i64;
    let colour = RGBColor(c[0], c[1], c[2]);
    let style = TextStyle::from(f)
        .color(&colour)
        .pos(Pos::new(HPos::Left, VPos::Top));
    let mut backend = BitMapBackend::with_buffer(data, (width as u32, height as u32));
    // Drawing into a buffer cannot fail; a missing glyph draws as a box.
    let _ = backend.draw_text(text, &style, (x as i32, top as i32));
    let _ = backend.present();
}

/// Whether the embedded font has a glyph for every character of `text`
/// (the layout of a missing one falls back to the font's empty box).
#[cfg(test)]
pub(crate) fn has_glyphs(text: &str) -> bool {
    text.chars().all(|ch| {
        let mut buf = vec![255u8; 3 * 40 * 40];
        draw_text(&mut buf, (40, 40), (4, 4), &ch.to_string(), 3, [0, 0, 0]);
        let tofu = {
            let mut b = vec![255u8; 3 * 40 * 40];
            draw_text(&mut b, (40, 40), (4, 4), "\u{FFFF}", 3, [0, 0, 0]);
            b
        };
        ch == ' ' || buf != tofu
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ink(buf: &[u8]) -> Vec<(usize, usize)> {
        buf.chunks(3)
            .enumerate()
            .filter(|(_, p)| p.iter().all(|&v| v < 128))
            .map(|(i, _)| (i % 60, i / 60))
            .collect()
    }

    #[test]
    fn capitals_sit_between_y_and_the_baseline() {
        let mut buf = vec![255u8; 3 * 60 * 40];
        draw_text(&mut buf, (60, 40), (5, 10), "HE", 2, [0, 0, 0]);
        let px = ink(&buf);
        assert!(px.len() > 40, "{} ink pixels", px.len());
        let (ymin, ymax) = px
            .iter()
            .fold((usize::MAX, 0), |(a, b), p| (a.min(p.1), b.max(p.1)));
        // Caps from y = 10 to the baseline at y + 14 (one pixel of rounding).
        assert!(
            (9..=11).contains(&ymin) && (22..=24).contains(&ymax),
            "rows {ymin}..{ymax}"
        );
        let xmax = px.iter().map(|p| p.0).max().unwrap() as i64;
        let w = text_width("HE", 2);
        assert!(xmax >= 5 + w / 2 && xmax < 5 + w, "x max {xmax}, width {w}");
    }

    #[test]
    fn widths_grow_with_text_and_scale() {
        assert_eq!(text_width("", 3), 0);
        let (a, ab) = (text_width("8", 1), text_width("88", 1));
        assert!(a >= 4 && ab >= 2 * a - 1 && ab <= 2 * a + 1, "{a} {ab}");
        let big = text_width("88", 3);
        assert!((big - 3 * ab).abs() <= 3, "{big} vs {}", 3 * ab);
    }

    #[test]
    fn every_label_character_has_a_glyph() {
        assert!(has_glyphs("0123456789.-+e cd/m2L=θφ°"));
        assert!(!has_glyphs("中"));
    }
}
