//! Log-log line plots as SVG (plotters), written atomically. Text is laid
//! out with the embedded font of `io/text.rs`.

use plotters::prelude::*;

/// One named line of a plot.
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points `(x, y)`, both > 0.
    pub points: Vec<(f64, f64)>,
    /// Dashed reference line rather than data.
    pub dashed: bool,
}

/// Render a log-log plot to SVG text.
pub fn loglog_svg(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<String, String> {
    let pts = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|(x, y)| *x > 0.0 && *y > 0.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        return Err("nothing to plot".into());
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 2.0, y1 * 2.0);
    super::text::register_fonts();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        let palette = [BLUE, RED, GREEN, MAGENTA, CYAN, BLACK];
        for (k, s) in series.iter().enumerate() {
            let color = palette[k % palette.len()];
            let data: Vec<(f64, f64)> = s
                .points
                .iter()
                .copied()
                .filter(|(x, y)| *x > 0.0 && *y > 0.0)
                .collect();
            let style = color.stroke_width(2);
            if s.dashed {
                chart
                    .draw_series(DashedLineSeries::new(data, 8, 6, style))
                    .map_err(|e| e.to_string())?
                    .label(s.name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            } else {
                chart
                    .draw_series(LineSeries::new(data.clone(), style))
                    .map_err(|e| e.to_string())?
                    .label(s.name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
                chart
                    .draw_series(data.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                    .map_err(|e| e.to_string())?;
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loglog_plot_has_its_title_labels_and_legend() {
        let series = [
            Series {
                name: "max |z|".into(),
                points: vec![(0.1, 3.0), (1.0, 1.0), (10.0, 0.3)],
                dashed: false,
            },
            Series {
                name: "1/sqrt(T)".into(),
                points: vec![(0.1, 3.0), (10.0, 0.3)],
                dashed: true,
            },
        ];
        let svg = loglog_svg("Error against time", "T [s]", "error [lx]", &series).unwrap();
        for text in [
            "Error against time",
            "T [s]",
            "error [lx]",
            "max |z|",
            "1/sqrt(T)",
        ] {
            assert!(svg.contains(text), "{text} missing");
        }
        assert!(svg.matches("<circle").count() >= 3);
        assert!(loglog_svg("t", "x", "y", &[]).is_err());
    }
}
