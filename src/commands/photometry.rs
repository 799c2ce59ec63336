//! `lumest photometry FILE`: the summary of a photometric file (flux, peak
//! intensity and its direction, beam and field angles, symmetry) and a polar
//! candela plot of the C0-C180 and C90-C270 planes, as photometric viewers show.

use crate::io::photometry::{PhotometricType, Photometry};
use crate::io::{format_fixed, format_number, write_atomic};
use crate::light::Goniometric;
use anyhow::Context;
use clap::Args;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Arguments of `lumest photometry`.
#[derive(Args, Clone, Debug)]
pub struct PhotometryArgs {
    /// An IES (`.ies`) or EULUMDAT (`.ldt`) file.
    pub file: PathBuf,
    /// Write a polar candela plot (SVG) of the main planes here.
    #[arg(long)]
    pub plot: Option<String>,
}

/// In-plane intensity \[cd\] at angle `theta` \[deg\] in `[-180, 180]` from the
/// nadir, in the plane of C-angle `c` \[deg\] (positive `theta`: that C-plane,
/// negative: the opposite one).
pub fn plane_intensity(g: &Goniometric, c: f64, theta: f64) -> f64 {
    let (c, gamma) = if theta >= 0.0 {
        (c, theta)
    } else {
        ((c + 180.0) % 360.0, -theta)
    };
    let d = glam::DVec3::new(
        gamma.to_radians().sin() * c.to_radians().cos(),
        gamma.to_radians().sin() * c.to_radians().sin(),
        -gamma.to_radians().cos(),
    );
    g.intensity(d)
}

/// Full angle \[deg\] about the peak of a plane's curve (0.1 degree steps)
/// within which the intensity stays at or above `fraction` of the plane's
/// peak: the beam angle at 0.5, the field angle at 0.1 (CIE / IES
/// definitions); `None` for a dark plane.
pub fn spread_angle(g: &Goniometric, c: f64, fraction: f64) -> Option<f64> {
    let thetas: Vec<f64> = (-1800..=1800).map(|k| k as f64 / 10.0).collect();
    let vals: Vec<f64> = thetas.iter().map(|&t| plane_intensity(g, c, t)).collect();
    let (peak_at, peak) =
        vals.iter().enumerate().fold(
            (0, 0.0),
            |(k, m), (j, &v)| if v > m { (j, v) } else { (k, m) },
        );
    if peak <= 0.0 {
        return None;
    }
    let limit = fraction * peak;
    let mut lo = peak_at;
    while lo > 0 && vals[lo - 1] >= limit {
        lo -= 1;
    }
    let mut hi = peak_at;
    while hi + 1 < vals.len() && vals[hi + 1] >= limit {
        hi += 1;
    }
    Some(thetas[hi] - thetas[lo])
}

/// The summary lines of a photometric file: the upright luminaire (with
/// an IES tilt table, its factor at tilt 0 applied).
pub fn summary(p: &Photometry) -> Vec<String> {
    let tilt = p.upright_tilt_factor();
    let g = Goniometric::new(p, tilt);
    let mut lines = vec![
        format!(
            "{}, type {:?}, {} horizontal x {} vertical angles, symmetry {:?}",
            p.format,
            p.kind,
            p.h_angles.len(),
            p.v_angles.len(),
            p.symmetry()
        ),
        match p.lamp_lumens {
            Some(lm) => format!(
                "flux of the table {} lm; lamps {} lm; light output ratio {}",
                format_fixed(g.power(), 1),
                format_number(lm),
                format_fixed(g.power() / lm, 4)
            ),
            None => format!(
                "flux of the table {} lm (absolute photometry)",
                format_fixed(g.power(), 1)
            ),
        },
    ];
    if let Some(t) = &p.tilt {
        lines.push(format!(
            "TILT=INCLUDE, lamp {:?}: factors {} at {} deg; shown upright (factor {}), in a scene at the light's installed tilt",
            t.geometry,
            t.factors.iter().map(|f| format_number(*f)).collect::<Vec<_>>().join(", "),
            t.angles.iter().map(|f| format_number(*f)).collect::<Vec<_>>().join(", "),
            format_number(tilt)
        ));
    }
    let (mut best, mut at) = (0.0, (0.0, 0.0));
    for (a, row) in p.h_angles.iter().zip(&p.candela) {
        for (v, &i) in p.v_angles.iter().zip(row) {
            let i = i * tilt;
            if i > best {
                best = i;
                at = (*a, *v);
            }
        }
    }
    let (h, v) = match p.kind {
        PhotometricType::C => ("C", "gamma"),
        PhotometricType::B | PhotometricType::A => ("H", "V"),
    };
    lines.push(format!(
        "max intensity {} cd at {h} = {} deg, {v} = {} deg",
        format_fixed(best, 1),
        at.0,
        at.1
    ));
    if p.kind == PhotometricType::C {
        for c in [0.0, 90.0] {
            let beam = spread_angle(&g, c, 0.5).map_or("-".into(), |a| format!("{a:.1} deg"));
            let field = spread_angle(&g, c, 0.1).map_or("-".into(), |a| format!("{a:.1} deg"));
            lines.push(format!(
                "plane C{c}-C{}: beam angle (50 %) {beam}, field angle (10 %) {field}",
                c + 180.0
            ));
        }
    }
    let o = p.opening;
    lines.push(if o.width == 0.0 && o.length == 0.0 {
        "luminous opening: none given (a point source)".to_string()
    } else if o.round && o.length == 0.0 {
        format!(
            "luminous opening: disc of diameter {} m, height {} m",
            o.width, o.height
        )
    } else if o.shape == crate::io::photometry::OpeningShape::Rectangle {
        format!(
            "luminous opening: {} m x {} m, height {} m",
            o.width, o.length, o.height
        )
    } else {
        format!(
            "luminous opening: {}, width {} m, length {} m, height {} m",
            o.shape.name(o.width, o.length, o.height),
            o.width,
            o.length,
            o.height
        )
    });
    lines
}

/// A polar candela plot (SVG) of the C0-C180 and C90-C270 planes.
pub fn polar_svg(p: &Photometry, title: &str) -> Result<String, String> {
    let g = Goniometric::new(p, p.upright_tilt_factor());
    let curve = |c: f64| -> Vec<(f64, f64)> {
        (-360..=360)
            .map(|k| {
                let t = k as f64 / 2.0;
                let i = plane_intensity(&g, c, t);
                (i * t.to_radians().sin(), -i * t.to_radians().cos())
            })
            .collect()
    };
    let m = g.max_intensity().max(1e-300) * 1.1;
    crate::io::text::register_fonts();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (640, 680)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(-m..m, -m..m)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("cd (horizontal)")
            .y_desc("cd (nadir down)")
            .draw()
            .map_err(|e| e.to_string())?;
        for k in 1..=4 {
            let r = m / 1.1 * k as f64 / 4.0;
            let ring: Vec<(f64, f64)> = (0..=72)
                .map(|a| {
                    let t = (a as f64 * 5.0).to_radians();
                    (r * t.cos(), r * t.sin())
                })
                .collect();
            chart
                .draw_series(LineSeries::new(ring, BLACK.mix(0.2)))
                .map_err(|e| e.to_string())?;
        }
        for (c, color, name) in [(0.0, RED, "C0-C180"), (90.0, BLUE, "C90-C270")] {
            chart
                .draw_series(LineSeries::new(curve(c), color.stroke_width(2)))
                .map_err(|e| e.to_string())?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
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

/// Run `lumest photometry`.
pub fn photometry(a: &PhotometryArgs) -> anyhow::Result<()> {
    if let Some(out) = &a.plot {
        super::outputs::check_outputs(&[a.file.as_path()], &[("--plot", Path::new(out))])?;
    }
    let p = crate::io::photometry::read(&a.file)?;
    for line in summary(&p) {
        println!("{line}");
    }
    if let Some(out) = &a.plot {
        let title = format!("{} ({})", a.file.display(), p.format);
        let svg = polar_svg(&p, &title).map_err(|e| anyhow::anyhow!("polar plot: {e}"))?;
        write_atomic(out, svg.as_bytes()).with_context(|| format!("writing {out}"))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::photometry::ies;

    #[test]
    fn summary_of_a_cosine_downlight_has_its_closed_form_angles() {
        // I = I0 cos(gamma) over 0-90: flux pi I0; 50 % at gamma = 60 deg
        // (beam 120 deg), 10 % at acos(0.1) = 84.26 deg (field 168.5 deg).
        let v: Vec<String> = (0..=90).map(|g| g.to_string()).collect();
        let i: Vec<String> = (0..=90)
            .map(|g| format!("{:.17e}", 1000.0 * f64::from(g).to_radians().cos()))
            .collect();
        let text = format!(
            "IESNA:LM-63-2002\n[TEST] t\nTILT=NONE\n1 -1 1 91 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
            v.join(" "),
            i.join(" ")
        );
        let p = ies::parse(&text, "c.ies").unwrap();
        let g = Goniometric::new(&p, 1.0);
        let beam = spread_angle(&g, 0.0, 0.5).unwrap();
        let field = spread_angle(&g, 90.0, 0.1).unwrap();
        assert!((beam - 120.0).abs() <= 0.2, "{beam}");
        assert!(
            (field - 2.0 * 0.1f64.acos().to_degrees()).abs() <= 0.2,
            "{field}"
        );
        let s = summary(&p).join("\n");
        assert!(
            s.contains("max intensity 1000.0 cd at C = 0 deg, gamma = 0 deg"),
            "{s}"
        );
        // The flux of the bilinear table is pi I0 to within 1e-4.
        assert!((g.power() / (std::f64::consts::PI * 1000.0) - 1.0).abs() < 1e-4);
        assert!(
            s.contains(&format!("flux of the table {:.1} lm", g.power())),
            "{s}"
        );
        let svg = polar_svg(&p, "cosine").unwrap();
        assert!(svg.contains("C0-C180") && svg.contains("C90-C270") && svg.contains("cosine"));
    }
}
