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

/// Full angle \[deg\] about the peak of a plane's curve within which the
/// intensity stays at or above `fraction` of the plane's peak: the beam
/// angle at 0.5, the field angle at 0.1 (CIE / IES definitions); `None`
/// for a dark plane. The curve is followed round the whole circle of the
/// plane (through the zenith: an uplight's beam about gamma = 180 is
/// whole), sampled every 0.1 degree, each crossing placed by linear
/// interpolation between samples; 360 where the intensity never falls
/// below the limit.
pub fn spread_angle(g: &Goniometric, c: f64, fraction: f64) -> Option<f64> {
    const STEP: f64 = 0.1;
    let n = 3600usize;
    let vals: Vec<f64> = (0..n)
        .map(|k| plane_intensity(g, c, -180.0 + k as f64 * STEP))
        .collect();
    let (peak_at, peak) =
        vals.iter().enumerate().fold(
            (0, 0.0),
            |(k, m), (j, &v)| if v > m { (j, v) } else { (k, m) },
        );
    if peak <= 0.0 {
        return None;
    }
    let limit = fraction * peak;
    // Degrees from the peak to the first crossing below the limit, going
    // up (`+1`) or down (`n - 1`) the circle.
    let reach = |step: usize| -> Option<f64> {
        (1..n).find_map(|j| {
            let (a, b) = (
                vals[(peak_at + (j - 1) * step) % n],
                vals[(peak_at + j * step) % n],
            );
            (b < limit).then(|| (j as f64 - 1.0 + (a - limit) / (a - b)) * STEP)
        })
    };
    Some(match (reach(1), reach(n - 1)) {
        (Some(up), Some(down)) => (up + down).min(360.0),
        _ => 360.0,
    })
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
                match g.power() / lm {
                    r if r.is_finite() => format_fixed(r, 4),
                    _ => "out of range".to_string(),
                }
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
    // As a scene refuses it (an infinite axis would also stall the plot).
    let g = Goniometric::new(&p, p.upright_tilt_factor());
    if let Some(e) = g.range_error() {
        let here = match g.max_intensity() {
            m if m.is_finite() => format!("the largest is {} cd", format_number(m)),
            _ => "the intensities overflow".to_string(),
        };
        anyhow::bail!(
            "{}: {e}; here {here} (check the candela multiplier, the ballast and conversion \
             factors and the candela values)",
            a.file.display(),
        );
    }
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

    /// A rotational table every 0.5 degrees over `gammas` (degrees) of
    /// `i(gamma)` \[cd\].
    fn rotational(gammas: std::ops::RangeInclusive<u32>, i: impl Fn(f64) -> f64) -> Goniometric {
        let g: Vec<f64> = gammas.map(|k| f64::from(k) / 2.0).collect();
        let text = format!(
            "IESNA:LM-63-2002\n[TEST] t\nTILT=NONE\n1 -1 1 {} 1 1 2 0 0 0\n1 1 0\n{}\n0\n{}\n",
            g.len(),
            g.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(" "),
            g.iter()
                .map(|&x| format!("{:.17e}", i(x)))
                .collect::<Vec<_>>()
                .join(" ")
        );
        Goniometric::new(&ies::parse(&text, "t.ies").unwrap(), 1.0)
    }

    #[test]
    fn beam_and_field_angles_follow_the_curve_through_the_zenith() {
        // I = I0 cos^4 of the angle from the beam's axis: half at
        // acos(0.5^(1/4)), a tenth at acos(0.1^(1/4)) from it. Read with
        // the plane's angle from -180 to 180 and no wrap, an uplight's beam
        // about gamma = 180 came out cut in half (32.7 against 65.5
        // degrees), and every angle floored to the 0.1 degree grid.
        let (beam, field) = (
            2.0 * 0.5f64.powf(0.25).acos().to_degrees(),
            2.0 * 0.1f64.powf(0.25).acos().to_degrees(),
        );
        let cos4 = |a: f64| 1000.0 * a.to_radians().cos().max(0.0).powi(4);
        for (what, g) in [
            ("downlight", rotational(0..=180, cos4)),
            ("uplight", rotational(180..=360, |x| cos4(180.0 - x))),
            (
                "uplight over 0-180",
                rotational(0..=360, |x| cos4(180.0 - x)),
            ),
        ] {
            for c in [0.0, 90.0] {
                let b = spread_angle(&g, c, 0.5).unwrap();
                let f = spread_angle(&g, c, 0.1).unwrap();
                assert!(
                    (b - beam).abs() < 0.02 && (f - field).abs() < 0.02,
                    "{what}: {b} {f}"
                );
            }
        }
        // A ring 10 degrees off the axis, down or up: in a plane its two
        // lobes meet above half the peak on the axis, so the beam spans
        // both, 2 (10 + acos(0.5^(1/4))).
        for (what, g) in [
            ("ring downlight", rotational(0..=360, |x| cos4(10.0 - x))),
            ("ring uplight", rotational(0..=360, |x| cos4(170.0 - x))),
        ] {
            let b = spread_angle(&g, 0.0, 0.5).unwrap();
            let f = spread_angle(&g, 0.0, 0.1).unwrap();
            assert!(
                (b - beam - 20.0).abs() < 0.02 && (f - field - 20.0).abs() < 0.02,
                "{what}: {b} {f}"
            );
        }
        // Above half the peak all round: the whole circle.
        let g = rotational(0..=360, |x| 1000.0 - x);
        assert_eq!(spread_angle(&g, 0.0, 0.5), Some(360.0));
    }
}
