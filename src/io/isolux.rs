//! Isolux plots of a grid (plotters, PNG and SVG from one drawing): the
//! illuminance \[lx\] as a false-colour map (viridis, [`super::image::colour_map`])
//! with a labelled colour scale, isolux lines at round levels (marching
//! squares, [`crate::grid::contour`]) labelled with their value, the grid's
//! cells as a dashed rectangle, the room's outline (the scene's surfaces
//! projected onto the grid's plane) and the luminaires' positions.
//!
//! The map between the grid's points (cell centres) is the bilinear
//! interpolate of the lattice, held constant from the outer points to the
//! cells' edges; it is drawn as small rectangles (about 3 px in a PNG; up
//! to 8 per cell and side in an SVG, which keeps the file small), so the
//! colour at a point is the interpolate at its rectangle's centre. Both
//! axes have the same scale (metres), short of very long, thin grids.

use super::image::{ColourScale, colour_map};
use crate::grid::contour::{isolines, levels};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// A line through points `(x, y)` \[m\].
pub type Polyline = Vec<(f64, f64)>;

/// A line of the room's outline in plot coordinates \[m\].
#[derive(Clone, Debug, PartialEq)]
pub struct Outline {
    /// Corners in order.
    pub points: Vec<(f64, f64)>,
    /// Whether the last corner joins the first.
    pub closed: bool,
    /// Drawn heavier (the room's walls).
    pub heavy: bool,
}

/// What an isolux plot shows.
#[derive(Clone, Debug, PartialEq)]
pub struct IsoluxPlot {
    /// Title line.
    pub title: String,
    /// Axis names (`x [m]`, ...).
    pub x_label: String,
    /// Second axis name.
    pub y_label: String,
    /// Lattice coordinates of the points \[m\], increasing.
    pub xs: Vec<f64>,
    /// Second lattice coordinates \[m\], increasing.
    pub ys: Vec<f64>,
    /// Illuminance \[lx\] at node `(i, j)`: `z[j xs.len() + i]`; NaN where no point.
    pub z: Vec<f64>,
    /// The grid's cells `(x0, x1, y0, y1)` \[m\].
    pub bounds: (f64, f64, f64, f64),
    /// The room's outline.
    pub outlines: Vec<Outline>,
    /// Luminaire positions \[m\].
    pub luminaires: Vec<(f64, f64)>,
}

/// Canvas width \[px\].
const WIDTH: u32 = 960;
/// Width of the colour scale's area \[px\].
const BAR_W: u32 = 150;
/// Label areas and margins \[px\].
const Y_LABEL_W: u32 = 64;
const X_LABEL_H: u32 = 48;
const MARGIN: u32 = 16;
const TITLE_H: u32 = 40;

impl IsoluxPlot {
    /// The finite values' range, or `None` when no value is finite.
    fn range(&self) -> Option<(f64, f64)> {
        let (lo, hi) = self
            .z
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        (lo <= hi).then_some((lo, hi))
    }

    /// The colour scale: the data's range (widened when flat).
    pub fn scale(&self) -> ColourScale {
        let (lo, hi) = self.range().unwrap_or((0.0, 1.0));
        ColourScale::from_data(&[lo, hi], false)
    }

    /// The isolux levels \[lx\]: about 7 round values inside the range.
    pub fn levels(&self) -> Vec<f64> {
        self.range()
            .map_or(Vec::new(), |(lo, hi)| levels(lo, hi, 7))
    }

    /// The isolines of every level: `(level, polylines)`.
    pub fn contours(&self) -> Vec<(f64, Vec<Polyline>)> {
        self.levels()
            .into_iter()
            .map(|l| (l, isolines(&self.xs, &self.ys, &self.z, l)))
            .collect()
    }

    /// The interpolated value at `(x, y)`: bilinear between nodes, constant
    /// beyond the outer ones; at a cell with a missing corner, the nearest
    /// node's value (`None` when that is missing too).
    pub fn value_at(&self, x: f64, y: f64) -> Option<f64> {
        let (ix, tx) = locate(&self.xs, x);
        let (iy, ty) = locate(&self.ys, y);
        let nx = self.xs.len();
        let at = |i: usize, j: usize| self.z[j * nx + i];
        let (ix1, iy1) = ((ix + 1).min(nx - 1), (iy + 1).min(self.ys.len() - 1));
        let c = [at(ix, iy), at(ix1, iy), at(ix, iy1), at(ix1, iy1)];
        if c.iter().all(|v| v.is_finite()) {
            let bottom = c[0] + tx * (c[1] - c[0]);
            let top = c[2] + tx * (c[3] - c[2]);
            return Some(bottom + ty * (top - bottom));
        }
        let i = if tx < 0.5 { ix } else { ix1 };
        let j = if ty < 0.5 { iy } else { iy1 };
        Some(at(i, j)).filter(|v| v.is_finite())
    }

    /// The shown area `(x0, x1, y0, y1)` \[m\]: the grid, the outline and the
    /// luminaires (no farther than half the grid's size beyond it), plus 4 %.
    fn view(&self) -> (f64, f64, f64, f64) {
        let (gx0, gx1, gy0, gy1) = self.bounds;
        let reach = 0.5 * (gx1 - gx0).max(gy1 - gy0);
        let (mut x0, mut x1, mut y0, mut y1) = self.bounds;
        // Luminaires farther out than that are left out of the view.
        let near = |&&(x, y): &&(f64, f64)| {
            x >= gx0 - reach && x <= gx1 + reach && y >= gy0 - reach && y <= gy1 + reach
        };
        let others = self
            .outlines
            .iter()
            .flat_map(|o| o.points.iter())
            .chain(self.luminaires.iter().filter(near));
        for &(x, y) in others {
            x0 = x0.min(x.max(gx0 - reach));
            x1 = x1.max(x.min(gx1 + reach));
            y0 = y0.min(y.max(gy0 - reach));
            y1 = y1.max(y.min(gy1 + reach));
        }
        let pad = 0.04 * (x1 - x0).max(y1 - y0);
        (x0 - pad, x1 + pad, y0 - pad, y1 + pad)
    }

    /// Plot width and height \[px\] with equal scales on both axes (height
    /// kept within 160-720 px).
    fn plot_size(&self) -> (u32, u32) {
        let (x0, x1, y0, y1) = self.view();
        let avail = WIDTH - BAR_W - Y_LABEL_W - 2 * MARGIN;
        let h = (avail as f64 * (y1 - y0) / (x1 - x0)).round();
        if h > 720.0 {
            ((avail as f64 * 720.0 / h).round() as u32, 720)
        } else {
            (avail, h.max(160.0) as u32)
        }
    }

    /// Canvas size \[px\].
    pub fn size(&self) -> (u32, u32) {
        let (_, h) = self.plot_size();
        (WIDTH, TITLE_H + MARGIN + h + X_LABEL_H + MARGIN)
    }

    /// The plot as SVG text.
    pub fn svg(&self) -> Result<String, String> {
        super::text::register_fonts();
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, self.size()).into_drawing_area();
            self.draw(&root, false)?;
            root.present().map_err(|e| e.to_string())?;
        }
        Ok(svg)
    }

    /// The plot as PNG bytes (8-bit RGB).
    pub fn png(&self) -> Result<Vec<u8>, String> {
        super::text::register_fonts();
        let (w, h) = self.size();
        let mut buf = vec![255u8; 3 * (w * h) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            self.draw(&root, true)?;
            root.present().map_err(|e| e.to_string())?;
        }
        let img = super::image::Rgb8Image {
            width: w as usize,
            height: h as usize,
            data: buf,
        };
        img.encode_png().map_err(|e| e.to_string())
    }

    /// Draw on `root`; `fine`: small map rectangles (raster output).
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        fine: bool,
    ) -> Result<(), String> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        root.fill(&WHITE).map_err(err)?;
        let (w, _) = self.size();
        let (pw, ph) = self.plot_size();
        let (left, right) = root.split_horizontally(w - BAR_W);
        let (x0, x1, y0, y1) = self.view();
        let mut chart = ChartBuilder::on(&left)
            .caption(&self.title, ("sans-serif", 18))
            .margin_left(MARGIN)
            .margin_top(MARGIN)
            .margin_right(w - BAR_W - MARGIN - Y_LABEL_W - pw)
            .margin_bottom(MARGIN)
            .x_label_area_size(X_LABEL_H)
            .y_label_area_size(Y_LABEL_W)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .x_label_formatter(&|v| super::image::tick_label(*v))
            .y_label_formatter(&|v| super::image::tick_label(*v))
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(err)?;
        let scale = self.scale();
        // The false-colour map over the grid's cells.
        let (gx0, gx1, gy0, gy1) = self.bounds;
        let (nx, ny) = if fine {
            let px = |a: f64, b: f64, span: f64, p: u32| ((b - a) / span * p as f64 / 3.0).ceil();
            (
                px(gx0, gx1, x1 - x0, pw).max(1.0) as usize,
                px(gy0, gy1, y1 - y0, ph).max(1.0) as usize,
            )
        } else {
            let k = |n: usize| n * (48 / n.max(1)).clamp(1, 8);
            (k(self.xs.len()), k(self.ys.len()))
        };
        let (dx, dy) = ((gx1 - gx0) / nx as f64, (gy1 - gy0) / ny as f64);
        let mut cells = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (cx, cy) = (gx0 + (i as f64 + 0.5) * dx, gy0 + (j as f64 + 0.5) * dy);
                if let Some(v) = self.value_at(cx, cy) {
                    let [r, g, b] = colour_map(scale.fraction(v));
                    let (ax, ay) = (gx0 + i as f64 * dx, gy0 + j as f64 * dy);
                    cells.push(Rectangle::new(
                        [(ax, ay), (ax + dx, ay + dy)],
                        RGBColor(r, g, b).filled(),
                    ));
                }
            }
        }
        chart.draw_series(cells).map_err(err)?;
        // The grid's cells and the room's outline.
        let view = (x0, x1, y0, y1);
        let grid = [(gx0, gy0), (gx1, gy0), (gx1, gy1), (gx0, gy1), (gx0, gy0)];
        chart
            .draw_series(DashedLineSeries::new(grid, 6, 4, BLACK.stroke_width(1)))
            .map_err(err)?;
        for o in &self.outlines {
            let mut pts = o.points.clone();
            if o.closed && pts.len() > 2 {
                pts.push(pts[0]);
            }
            let style = if o.heavy {
                BLACK.stroke_width(3)
            } else {
                RGBColor(60, 60, 60).stroke_width(1)
            };
            let segs = pts
                .windows(2)
                .filter_map(|s| clip(s[0], s[1], view))
                .map(|(a, b)| PathElement::new(vec![a, b], style));
            chart.draw_series(segs).map_err(err)?;
        }
        // Isolux lines, each level labelled once on its longest line.
        let label_style = TextStyle::from(("sans-serif", 12).into_font())
            .pos(Pos::new(HPos::Center, VPos::Center));
        let contours = self.contours();
        // The levels' spacing: labels carry the digits that tell them apart.
        let step = contours
            .windows(2)
            .map(|w| w[1].0 - w[0].0)
            .fold(f64::INFINITY, f64::min);
        for (level, lines) in contours {
            let style = BLACK.stroke_width(if fine { 2 } else { 1 });
            chart
                .draw_series(lines.iter().map(|l| PathElement::new(l.clone(), style)))
                .map_err(err)?;
            if let Some(l) = lines.iter().max_by_key(|l| l.len()) {
                let at = l[l.len() / 2];
                let text = super::image::label_to(level, step);
                // On a white box, readable on any colour.
                let half = 4 * text.len() as i32 + 3;
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at(at)
                            + Rectangle::new([(-half, -8), (half, 8)], WHITE.mix(0.85).filled())
                            + Text::new(text, (0, 0), label_style.clone()),
                    ))
                    .map_err(err)?;
            }
        }
        // Luminaires: red rings.
        let inside = |&&(x, y): &&(f64, f64)| x >= x0 && x <= x1 && y >= y0 && y <= y1;
        chart
            .draw_series(
                self.luminaires
                    .iter()
                    .filter(inside)
                    .map(|&p| Circle::new(p, 5, RED.stroke_width(2))),
            )
            .map_err(err)?;
        self.draw_bar(&right, ph, &scale)
    }

    /// The colour scale: a strip from the smallest to the largest value,
    /// labelled in lx, the isolux levels marked across it.
    fn draw_bar<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        ph: u32,
        scale: &ColourScale,
    ) -> Result<(), String> {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let (_, h) = self.size();
        let top = TITLE_H + MARGIN;
        let bottom = h - top - ph;
        let mut bar = ChartBuilder::on(area)
            .margin_top(top)
            .margin_bottom(bottom)
            .margin_left(8)
            .margin_right(BAR_W - 8 - 24 - 70)
            .y_label_area_size(0)
            .right_y_label_area_size(70)
            .build_cartesian_2d(0.0..1.0, scale.min..scale.max)
            .map_err(err)?;
        bar.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc("E [lx]")
            .y_label_formatter(&|v| super::image::label_to(*v, (scale.max - scale.min) / 50.0))
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(err)?;
        let steps = 120;
        let dz = (scale.max - scale.min) / steps as f64;
        bar.draw_series((0..steps).map(|k| {
            let z = scale.min + k as f64 * dz;
            let [r, g, b] = colour_map((k as f64 + 0.5) / steps as f64);
            Rectangle::new([(0.0, z), (1.0, z + dz)], RGBColor(r, g, b).filled())
        }))
        .map_err(err)?;
        bar.draw_series(
            self.levels()
                .into_iter()
                .map(|l| PathElement::new(vec![(0.0, l), (1.0, l)], BLACK.stroke_width(1))),
        )
        .map_err(err)?;
        bar.draw_series(std::iter::once(Rectangle::new(
            [(0.0, scale.min), (1.0, scale.max)],
            BLACK.stroke_width(1),
        )))
        .map_err(err)?;
        Ok(())
    }
}

/// Index `i` of the lattice interval holding `x` and the fraction `t` in
/// it (clamped to the ends: `t = 0` before the first, 1 after the last).
fn locate(l: &[f64], x: f64) -> (usize, f64) {
    if l.len() < 2 || x <= l[0] {
        return (0, 0.0);
    }
    let k = l.len();
    if x >= l[k - 1] {
        return (k - 2, 1.0);
    }
    let i = l.partition_point(|&v| v <= x) - 1;
    (i, (x - l[i]) / (l[i + 1] - l[i]))
}

/// The part of segment `a`-`b` inside the rectangle `(x0, x1, y0, y1)`
/// (Liang-Barsky), if any.
fn clip(
    a: (f64, f64),
    b: (f64, f64),
    (x0, x1, y0, y1): (f64, f64, f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6 x 4 m room, a 5 x 3 m grid of 10 x 6 points with `E = 100 + 50 x`.
    fn example() -> IsoluxPlot {
        let xs: Vec<f64> = (0..10).map(|i| 0.75 + 0.5 * i as f64).collect();
        let ys: Vec<f64> = (0..6).map(|j| 0.75 + 0.5 * j as f64).collect();
        let z = ys
            .iter()
            .flat_map(|_| xs.iter().map(|x| 100.0 + 50.0 * x))
            .collect();
        IsoluxPlot {
            title: "grid `a & <b>`".into(),
            x_label: "x [m]".into(),
            y_label: "y [m]".into(),
            xs,
            ys,
            z,
            bounds: (0.5, 5.5, 0.5, 3.5),
            outlines: vec![Outline {
                points: vec![(0.0, 0.0), (6.0, 0.0), (6.0, 4.0), (0.0, 4.0)],
                closed: true,
                heavy: true,
            }],
            luminaires: vec![(1.5, 1.0), (30.0, 1.0)],
        }
    }

    #[test]
    fn interpolates_between_and_holds_beyond_the_points() {
        let p = example();
        let v = p.value_at(1.0, 2.0).unwrap();
        assert!((v - 150.0).abs() < 1e-9, "{v}");
        assert!((p.value_at(0.5, 0.5).unwrap() - 137.5).abs() < 1e-9);
        assert!((p.value_at(9.0, 0.5).unwrap() - 362.5).abs() < 1e-9);
        let mut q = example();
        q.z[0] = f64::NAN;
        assert_eq!(q.value_at(0.8, 0.8), None);
        assert!((q.value_at(1.2, 0.8).unwrap() - 162.5).abs() < 1e-9);
    }

    /// Levels 150 .. 350 every 50 lx cross the map at x = 1, 2, 3, 4, 5:
    /// each is one straight line; the SVG holds their labels, the axis and
    /// scale texts (escaped), and the PNG decodes at the canvas size.
    #[test]
    fn svg_and_png_show_levels_scale_and_outline() {
        let p = example();
        assert_eq!(p.levels(), vec![150.0, 200.0, 250.0, 300.0, 350.0]);
        for (level, lines) in p.contours() {
            assert_eq!(lines.len(), 1);
            for q in &lines[0] {
                assert!((100.0 + 50.0 * q.0 - level).abs() < 1e-9);
            }
        }
        let svg = p.svg().unwrap();
        for text in [
            "150",
            "350",
            "E [lx]",
            "x [m]",
            "y [m]",
            "grid `a &amp; &lt;b&gt;`",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        assert!(!svg.contains("<b>"));
        let png = p.png().unwrap();
        let img = ::image::load_from_memory(&png).unwrap();
        assert_eq!((img.width(), img.height()), p.size());
        // The room (6 x 4 m, 4 % padding) keeps equal scales: plot height
        // over width is 4.48 / 6.48.
        let (w, h) = p.plot_size();
        assert!(
            ((h as f64 / w as f64) - 4.48 / 6.48).abs() < 0.01,
            "{w} x {h}"
        );
    }

    #[test]
    fn clipping() {
        let r = (0.0, 1.0, 0.0, 1.0);
        assert_eq!(
            clip((-1.0, 0.5), (2.0, 0.5), r),
            Some(((0.0, 0.5), (1.0, 0.5)))
        );
        assert_eq!(clip((2.0, 2.0), (3.0, 3.0), r), None);
        assert_eq!(
            clip((0.2, 0.2), (0.4, 0.4), r),
            Some(((0.2, 0.2), (0.4, 0.4)))
        );
    }
}
