//! `lumest render`: a luminance picture, each pixel a double local estimate
//! along the pixel's central ray of a pinhole camera.

use super::RunArgs;
use super::illuminance::{EstimatorKind, measure_with};
use crate::io::{ViewTable, format_number};
use clap::Args;
use glam::DVec3;
use std::path::PathBuf;

/// Arguments of `lumest render`.
#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML).
    #[arg(long)]
    pub scene: PathBuf,
    /// Camera position `x,y,z` (m).
    #[arg(long, allow_hyphen_values = true)]
    pub eye: String,
    /// Point the camera looks at `x,y,z` (m).
    #[arg(long, allow_hyphen_values = true)]
    pub look: String,
    /// Up direction `x,y,z`.
    #[arg(long, default_value = "0,0,1", allow_hyphen_values = true)]
    pub up: String,
    /// Horizontal field of view (degrees).
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    pub fov: f64,
    /// Image width (pixels).
    #[arg(long, default_value_t = 160, allow_negative_numbers = true)]
    pub width: usize,
    /// Image height (pixels).
    #[arg(long, default_value_t = 120, allow_negative_numbers = true)]
    pub height: usize,
    /// Output PNG (display image). Also written: the same name with `.hdr`
    /// (luminance in cd/m^2), `_false.png` (false colour with a scale bar) and
    /// `.csv` (luminance and standard error per view: per pixel for a pinhole;
    /// with a lens, per lens sample, and per pixel in `_pixels.csv`).
    #[arg(long)]
    pub out: String,
    /// Thin-lens depth of field: aperture radius (m) (0: pinhole).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub aperture: f64,
    /// Thin-lens focus distance along the viewing axis (m) (default: |look - eye|).
    #[arg(long, allow_negative_numbers = true)]
    pub focus: Option<f64>,
    /// Lens samples per pixel with `--aperture` (a stratified square grid: 1, 4, 9, 16, ...).
    #[arg(
        long = "lens-samples",
        default_value_t = 16,
        allow_negative_numbers = true
    )]
    pub lens_samples: usize,
    /// Display exposure: `auto` or a factor k (display value = k L, 1 = white).
    #[arg(long, default_value = "auto", allow_negative_numbers = true)]
    pub exposure: String,
    /// Estimator of the reflected light.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Local)]
    pub estimator: EstimatorKind,
    #[command(flatten)]
    pub run: RunArgs,
}

/// A thin lens: aperture radius \[m\], focus distance \[m\] along the viewing
/// axis, and `k` samples per pixel on a `sqrt(k) x sqrt(k)` grid of the
/// square mapped to the disc (Shirley-Chiu concentric map).
#[derive(Clone, Copy, Debug)]
pub struct Lens {
    pub aperture: f64,
    pub focus: f64,
    pub k: usize,
}

/// Shirley-Chiu concentric map of `[0,1)^2` onto the unit disc.
fn concentric_disc(u: [f64; 2]) -> (f64, f64) {
    let (a, b) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f64::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b),
        )
    };
    (r * phi.cos(), r * phi.sin())
}

/// The view table of a camera, row-major from the top-left pixel, `lens.k`
/// consecutive views per pixel with a lens (one without); columns
/// `px,py,x,y,z,dx,dy,dz`.
pub fn camera_views(
    eye: DVec3,
    look: DVec3,
    up: DVec3,
    fov_deg: f64,
    w: usize,
    h: usize,
    lens: Option<Lens>,
) -> anyhow::Result<ViewTable> {
    let fwd = (look - eye).normalize_or_zero();
    anyhow::ensure!(fwd != DVec3::ZERO, "--look must differ from --eye");
    let right = fwd.cross(up).normalize_or_zero();
    anyhow::ensure!(
        right != DVec3::ZERO,
        "--up must not be parallel to the viewing direction"
    );
    anyhow::ensure!(
        fov_deg > 0.0 && fov_deg < 180.0,
        "--fov must lie in (0, 180) degrees"
    );
    anyhow::ensure!(
        w > 0 && h > 0 && w.checked_mul(h).is_some_and(|n| n <= 4_000_000),
        "--width x --height must be positive and at most 4 Mpixel, got {w} x {h}"
    );
    if let Some(l) = lens {
        let m = (l.k as f64).sqrt().round().max(1.0) as u64;
        // (Checked: a product that wraps past 2^64 read 0 and passed.)
        let views = ((w * h) as u64)
            .checked_mul(m)
            .and_then(|v| v.checked_mul(m));
        anyhow::ensure!(
            views.is_some_and(|v| v <= super::MAX_VIEWS),
            "{w} x {h} pixels with {m} x {m} lens samples each make {} views; at most {} \
             (fewer pixels or lens samples)",
            views.map_or_else(|| "more than 2^64".to_string(), |v| v.to_string()),
            super::MAX_VIEWS
        );
    }
    let cam_up = right.cross(fwd);
    let tx = (0.5 * fov_deg).to_radians().tan();
    let ty = tx * h as f64 / w as f64;
    let mut t = ViewTable {
        headers: ["px", "py", "x", "y", "z", "dx", "dy", "dz"]
            .map(String::from)
            .to_vec(),
        ..ViewTable::default()
    };
    for j in 0..h {
        for i in 0..w {
            let u = (2.0 * (i as f64 + 0.5) / w as f64 - 1.0) * tx;
            let v = (1.0 - 2.0 * (j as f64 + 0.5) / h as f64) * ty;
            let d = (fwd + right * u + cam_up * v).normalize();
            let rays: Vec<(DVec3, DVec3)> = match lens {
                None => vec![(eye, d)],
                Some(l) => {
                    // Rays through the lens point meet the pinhole ray on the focal plane.
                    let focal = eye + d * (l.focus / d.dot(fwd));
                    let m = (l.k as f64).sqrt().round().max(1.0) as usize;
                    (0..m * m)
                        .map(|s| {
                            let uv = [
                                ((s % m) as f64 + 0.5) / m as f64,
                                ((s / m) as f64 + 0.5) / m as f64,
                            ];
                            let (x, y) = concentric_disc(uv);
                            let o = eye + (right * x + cam_up * y) * l.aperture;
                            (o, (focal - o).normalize())
                        })
                        .collect()
                }
            };
            for (o, d) in rays {
                let mut row = vec![i.to_string(), j.to_string()];
                row.extend([o.x, o.y, o.z, d.x, d.y, d.z].map(format_number));
                t.rows.push(row);
                t.lines.push(t.rows.len() as u64 + 1);
                t.views.push((o, d));
            }
        }
    }
    Ok(t)
}

fn vec3(s: &str, what: &str) -> anyhow::Result<DVec3> {
    let v = super::sobolev::parse_list(s).map_err(|e| anyhow::anyhow!("{what}: {e}"))?;
    anyhow::ensure!(v.len() == 3, "{what}: expected x,y,z, got `{s}`");
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// Run `lumest render`.
pub fn render(a: &RenderArgs) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.out != "-",
        "--out is the prefix of the image and table files render writes (PREFIX.png, PREFIX.hdr, ...): \
         `-` (standard output) cannot hold them"
    );
    let (eye, look) = (vec3(&a.eye, "--eye")?, vec3(&a.look, "--look")?);
    anyhow::ensure!(
        a.aperture.is_finite() && a.aperture >= 0.0,
        "--aperture must be >= 0"
    );
    let side = (a.lens_samples as f64).sqrt().round() as usize;
    anyhow::ensure!(
        a.lens_samples >= 1 && side * side == a.lens_samples,
        "--lens-samples must be a square number (1, 4, 9, 16, ...: a stratified square grid), got {}",
        a.lens_samples
    );
    let lens = (a.aperture > 0.0).then(|| Lens {
        aperture: a.aperture,
        focus: a.focus.unwrap_or_else(|| (look - eye).length()),
        k: a.lens_samples.max(1),
    });
    if let Some(l) = lens {
        anyhow::ensure!(
            l.focus.is_finite() && l.focus > 0.0,
            "--focus must be positive"
        );
    }
    let table = camera_views(
        eye,
        look,
        vec3(&a.up, "--up")?,
        a.fov,
        a.width,
        a.height,
        lens,
    )?;
    let per_pixel = table.views.len() / (a.width * a.height);
    let exposure = match a.exposure.as_str() {
        "auto" => crate::io::image::Exposure::Auto,
        k => {
            let k: f64 = k
                .parse()
                .map_err(|_| anyhow::anyhow!("--exposure: `auto` or a number, got `{k}`"))?;
            anyhow::ensure!(k.is_finite() && k > 0.0, "--exposure must be positive");
            crate::io::image::Exposure::Fixed(k)
        }
    };
    let base = a.out.strip_suffix(".png").unwrap_or(&a.out).to_string();
    let csv = format!("{base}.csv");
    let mut outs = vec![
        format!("{base}.png"),
        format!("{base}.hdr"),
        format!("{base}_false.png"),
        csv.clone(),
    ];
    if per_pixel > 1 {
        outs.push(format!("{base}_pixels.csv"));
    }
    let mut outputs: Vec<(&str, &std::path::Path)> = outs
        .iter()
        .map(|o| ("--out", std::path::Path::new(o)))
        .collect();
    // (The run checks the checkpoint against the CSV only; the images are
    // this command's own.)
    if let Some(ck) = &a.run.checkpoint {
        outputs.push(("--checkpoint", std::path::Path::new(ck)));
    }
    let referenced = crate::scene::referenced_files(&a.scene);
    let mut inputs = vec![a.scene.as_path()];
    inputs.extend(referenced.iter().map(|p| p.as_path()));
    super::outputs::check_outputs(&inputs, &outputs)?;
    let (job, r) = measure_with(
        &a.scene,
        None,
        Some(("camera", Some(table), &csv)),
        a.estimator,
        &a.run,
    )?;
    let view = |k: usize| {
        let (l, se) = job.view_receiver[k].map_or((0.0, 0.0), |j| {
            (
                r.direct[j] + r.tallies.estimated[j].mean(),
                r.tallies.estimated[j].std_error(),
            )
        });
        ((l + job.emitted[k]).max(0.0), se)
    };
    // A pixel is the mean of its lens views. Its standard error combines the
    // chains' noise (the mean of the views' standard errors: an upper bound
    // whatever their correlation) and the spread over the aperture (s^2 / K).
    let mut l = Vec::with_capacity(a.width * a.height);
    let mut se = Vec::with_capacity(a.width * a.height);
    for p in 0..a.width * a.height {
        let v: Vec<(f64, f64)> = (0..per_pixel).map(|s| view(p * per_pixel + s)).collect();
        let k = v.len() as f64;
        let mean = v.iter().map(|x| x.0).sum::<f64>() / k;
        let chain = v.iter().map(|x| x.1).sum::<f64>() / k;
        let spread = if v.len() > 1 {
            v.iter().map(|x| (x.0 - mean).powi(2)).sum::<f64>() / (k - 1.0) / k
        } else {
            0.0
        };
        l.push(mean);
        se.push((chain * chain + spread).sqrt());
    }
    if per_pixel > 1 {
        let mut text = String::from("px,py,L,L_stderr\n");
        for (p, (lv, sv)) in l.iter().zip(&se).enumerate() {
            text.push_str(&format!(
                "{},{},{},{}\n",
                p % a.width,
                p / a.width,
                format_number(*lv),
                format_number(*sv)
            ));
        }
        crate::io::write_atomic(&format!("{base}_pixels.csv"), text.as_bytes())?;
    }
    let img = crate::io::image::LuminanceImage::new(a.width, a.height, l)?;
    crate::io::image::write_hdr(&img, &format!("{base}.hdr"))?;
    crate::io::image::write_display_png(&img, &format!("{base}.png"), exposure)?;
    let scale = crate::io::image::ColourScale::from_data(&img.l, true);
    crate::io::image::write_false_colour_png(&img, &format!("{base}_false.png"), scale)?;
    eprintln!(
        "lumest: wrote {base}.png, {base}.hdr, {base}_false.png and {base}.csv{}",
        if per_pixel > 1 {
            format!(" (per view; per pixel: {base}_pixels.csv)")
        } else {
            String::new()
        }
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lens_rays_of_a_pixel_meet_on_the_focal_plane() {
        let (eye, look) = (DVec3::new(0.0, -2.0, 0.5), DVec3::new(0.0, 0.0, 0.5));
        let lens = Lens {
            aperture: 0.1,
            focus: 1.5,
            k: 4,
        };
        let t = camera_views(eye, look, DVec3::Z, 60.0, 3, 2, Some(lens)).unwrap();
        assert_eq!(t.views.len(), 3 * 2 * 4);
        let fwd = (look - eye).normalize();
        for pixel in t.views.chunks(4) {
            let meet: Vec<DVec3> = pixel
                .iter()
                .map(|&(o, d)| o + d * ((eye + fwd * 1.5 - o).dot(fwd) / d.dot(fwd)))
                .collect();
            for m in &meet {
                assert!((*m - meet[0]).length() < 1e-12);
            }
            // Lens points lie on the aperture disc around the eye, in the lens plane.
            for &(o, _) in pixel {
                assert!((o - eye).length() <= 0.1 + 1e-15 && (o - eye).dot(fwd).abs() < 1e-15);
            }
        }
        // Without a lens: one ray per pixel from the eye.
        let t = camera_views(eye, look, DVec3::Z, 60.0, 3, 2, None).unwrap();
        assert!(t.views.len() == 6 && t.views.iter().all(|v| v.0 == eye));
    }
}
