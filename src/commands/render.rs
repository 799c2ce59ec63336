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
    /// Camera position `x,y,z` [m].
    #[arg(long, allow_hyphen_values = true)]
    pub eye: String,
    /// Point the camera looks at `x,y,z` [m].
    #[arg(long, allow_hyphen_values = true)]
    pub look: String,
    /// Up direction `x,y,z`.
    #[arg(long, default_value = "0,0,1", allow_hyphen_values = true)]
    pub up: String,
    /// Horizontal field of view [degrees].
    #[arg(long, default_value_t = 60.0)]
    pub fov: f64,
    /// Image width [pixels].
    #[arg(long, default_value_t = 160)]
    pub width: usize,
    /// Image height [pixels].
    #[arg(long, default_value_t = 120)]
    pub height: usize,
    /// Output PNG (display image). Also written: the same name with `.hdr`
    /// (luminance in cd/m^2), `_false.png` (false colour with a scale bar) and
    /// `.csv` (per-pixel luminance and standard error).
    #[arg(long)]
    pub out: String,
    /// Display exposure: `auto` or a factor k (display value = k L, 1 = white).
    #[arg(long, default_value = "auto")]
    pub exposure: String,
    /// Estimator of the reflected light.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Local)]
    pub estimator: EstimatorKind,
    #[command(flatten)]
    pub run: RunArgs,
}

/// The view table of a pinhole camera, row-major from the top-left pixel;
/// columns `px,py,x,y,z,dx,dy,dz`.
pub fn camera_views(
    eye: DVec3,
    look: DVec3,
    up: DVec3,
    fov_deg: f64,
    w: usize,
    h: usize,
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
        w > 0 && h > 0 && w * h <= 4_000_000,
        "image size must be positive and at most 4 Mpixel"
    );
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
            let mut row = vec![i.to_string(), j.to_string()];
            row.extend([eye.x, eye.y, eye.z, d.x, d.y, d.z].map(format_number));
            t.rows.push(row);
            t.lines.push(t.rows.len() as u64 + 1);
            t.views.push((eye, d));
        }
    }
    Ok(t)
}

fn vec3(s: &str, what: &str) -> anyhow::Result<DVec3> {
    let v = super::sobolev::parse_list(s)?;
    anyhow::ensure!(v.len() == 3, "{what}: expected x,y,z, got `{s}`");
    Ok(DVec3::new(v[0], v[1], v[2]))
}

/// Run `lumest render`.
pub fn render(a: &RenderArgs) -> anyhow::Result<()> {
    let table = camera_views(
        vec3(&a.eye, "--eye")?,
        vec3(&a.look, "--look")?,
        vec3(&a.up, "--up")?,
        a.fov,
        a.width,
        a.height,
    )?;
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
    let (job, r) = measure_with(
        &a.scene,
        None,
        Some(("camera", Some(table), &csv)),
        a.estimator,
        &a.run,
    )?;
    let l: Vec<f64> = job
        .view_receiver
        .iter()
        .map(|rec| {
            rec.map_or(0.0, |j| {
                (r.direct[j] + r.tallies.indirect[j].mean()).max(0.0)
            })
        })
        .collect();
    let img = crate::io::image::LuminanceImage::new(a.width, a.height, l)?;
    crate::io::image::write_hdr(&img, &format!("{base}.hdr"))?;
    crate::io::image::write_display_png(&img, &format!("{base}.png"), exposure)?;
    let scale = crate::io::image::ColourScale::from_data(&img.l, true);
    crate::io::image::write_false_colour_png(&img, &format!("{base}_false.png"), scale)?;
    eprintln!("lumest: wrote {base}.png, {base}.hdr, {base}_false.png and {base}.csv");
    Ok(())
}
