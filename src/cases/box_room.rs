//! The closed box room: flux balance (absorbed equals emitted flux, no
//! leaks); `lumest validate box`.

use super::flux_balance::flux_balance;
use super::report::{Checkpoint, print_table, write_report};
use crate::geometry::shapes::{AaBox, Rect};
use crate::light::Light;
use crate::material::Material;
use crate::scene::{Scene, Sides, SurfaceSpec};
use crate::tally::{sidak_bound, zcheck};
use clap::Args;
use glam::DVec3;
use std::path::PathBuf;

/// Arguments of `lumest validate box`.
#[derive(Args, Clone, Debug)]
pub struct BoxArgs {
    /// Reflectance of the walls (the floor gets half of it, the ceiling 0.9 of it).
    #[arg(long, default_value_t = 0.8, allow_negative_numbers = true)]
    pub rho: f64,
    /// Number of chains.
    #[arg(long, default_value_t = 1_000_000, allow_negative_numbers = true)]
    pub chains: u64,
    /// Seed.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Folder for the table (CSV) and plot (SVG).
    #[arg(long, default_value = "validation_report")]
    pub report: PathBuf,
}

/// A 5 x 4 x 3 m box room with inward normals and a solid desk (an outward
/// box of reflectance 0.4), every length times `scale`: the one builder of
/// the box rooms of the validation cases ([`BoxRoom::furnished`] for
/// `validate box`, [`BoxRoom::plain`] for the `scaled` stress family).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxRoom {
    /// Reflectance of the four walls.
    pub walls: f64,
    /// Reflectance of the floor.
    pub floor: f64,
    /// Reflectance of the ceiling.
    pub ceiling: f64,
    /// Add the glossy partition (Phong `kd = 0.5`, `ks = 0.3`, `n = 20`,
    /// reflecting on both sides) at `x = 3.5`, 2 m wide and 1.8 m high.
    pub partition: bool,
    /// Add the second point light (200 cd at `(4, 2.5, 2.7)`) to the first
    /// (300 cd at `(1.5, 2, 2.7)`).
    pub second_light: bool,
    /// Length scale \[1\].
    pub scale: f64,
}

impl BoxRoom {
    /// The furnished room of `validate box`: walls `rho`, floor `rho / 2`,
    /// ceiling `0.9 rho`, the partition and both lights, unscaled.
    pub fn furnished(rho: f64) -> Self {
        Self {
            walls: rho,
            floor: 0.5 * rho,
            ceiling: 0.9 * rho,
            partition: true,
            second_light: true,
            scale: 1.0,
        }
    }

    /// The plain room of the `scaled` stress family: walls 0.8, floor 0.4,
    /// ceiling 0.7, no partition, one light, lengths times `s`.
    pub fn plain(s: f64) -> Self {
        Self {
            walls: 0.8,
            floor: 0.4,
            ceiling: 0.7,
            partition: false,
            second_light: false,
            scale: s,
        }
    }

    /// The room as a scene (surfaces: room, desk, partition; the lights in
    /// the order above).
    pub fn scene(&self) -> Scene {
        let s = self.scale;
        let wall = Material::Lambertian { rho: self.walls };
        let faces = [
            wall,
            wall,
            wall,
            wall,
            Material::Lambertian { rho: self.floor },
            Material::Lambertian { rho: self.ceiling },
        ];
        let mut surfaces = vec![
            SurfaceSpec::Box(
                "room".into(),
                AaBox {
                    lo: DVec3::ZERO,
                    hi: DVec3::new(5.0, 4.0, 3.0) * s,
                },
                Sides::Back,
                faces,
            ),
            SurfaceSpec::Box(
                "desk".into(),
                AaBox {
                    lo: DVec3::new(1.0, 1.0, 0.0) * s,
                    hi: DVec3::new(2.6, 1.8, 0.75) * s,
                },
                Sides::Front,
                [Material::Lambertian { rho: 0.4 }; 6],
            ),
        ];
        if self.partition {
            surfaces.push(SurfaceSpec::Rect(
                "partition".into(),
                Rect::new(
                    DVec3::new(3.5, 0.0, 0.0) * s,
                    DVec3::Y * 2.0 * s,
                    DVec3::Z * 1.8 * s,
                )
                .expect("rect"),
                Sides::Both,
                Material::Phong {
                    kd: 0.5,
                    ks: 0.3,
                    n: 20.0,
                },
            ));
        }
        let mut lights = vec![Light::Point {
            p: DVec3::new(1.5, 2.0, 2.7) * s,
            i: 300.0,
        }];
        if self.second_light {
            lights.push(Light::Point {
                p: DVec3::new(4.0, 2.5, 2.7) * s,
                i: 200.0,
            });
        }
        Scene::build(surfaces, lights).expect("a valid programmatic scene")
    }
}

/// The furnished test room of `validate box` ([`BoxRoom::furnished`]): a
/// 5 x 4 x 3 m box with inward normals, a solid desk (an outward box), a
/// partition rectangle reflecting on both sides, and two point lights.
pub fn box_room(rho: f64) -> Scene {
    BoxRoom::furnished(rho).scene()
}

/// `lumest validate box`: flux balance at growing numbers of chains (each
/// run independent), error against run time, and the per-surface table of
/// the largest run.
pub fn validate_box(a: &BoxArgs) -> anyhow::Result<()> {
    anyhow::ensure!((0.0..1.0).contains(&a.rho), "--rho must lie in [0, 1)");
    anyhow::ensure!(a.chains >= 64, "--chains must be at least 64");
    let scene = box_room(a.rho);
    eprintln!("lumest: scene: {}", scene.summary());
    let mut rows = Vec::new();
    let mut last = None;
    // Chains that escaped or met a black side over all five runs (the last
    // run's alone were checked before: a reviewer's find).
    let (mut escaped, mut back_side) = (0, 0);
    for k in (0..5).rev() {
        let chains = (a.chains >> k).max(64);
        let t0 = std::time::Instant::now();
        let fb = flux_balance(&scene, chains, 64, a.seed + k);
        let secs = t0.elapsed().as_secs_f64();
        let (m, se) = (fb.total.mean(), fb.total.std_error());
        let err = (m - fb.emitted).abs() / fb.emitted;
        let r = se / m;
        rows.push(Checkpoint {
            time: secs,
            chains,
            batches: fb.total.count(),
            rms_err: err,
            max_err: err,
            rms_r: r,
            max_z: zcheck::z_score(m, se, fb.emitted).abs(),
            fom: crate::tally::figure_of_merit(r, secs),
        });
        escaped += fb.escaped;
        back_side += fb.back_side;
        last = Some(fb);
    }
    let fb = last.expect("five runs");
    println!("Closed box room: absorbed against emitted flux [lm], independent runs:");
    print_table(&rows);
    write_report(
        &a.report,
        "box_flux",
        &rows,
        "closed box room: flux balance against run time",
    )?;
    println!(
        "{:>16} {:>14} {:>12}",
        "surface", "absorbed_lm", "stderr_lm"
    );
    for (s, w) in scene.surfaces.iter().zip(&fb.absorbed) {
        println!("{:>16} {:>14.6} {:>12.3e}", s.name, w.mean(), w.std_error());
    }
    let z = zcheck::z_score(fb.total.mean(), fb.total.std_error(), fb.emitted);
    println!(
        "absorbed {:.6} +- {:.3e} lm, emitted {:.6} lm: z = {z:.2}; chains that escaped: {}, met a black side: {} (over the five runs: {escaped}, {back_side})",
        fb.total.mean(),
        fb.total.std_error(),
        fb.emitted,
        fb.escaped,
        fb.back_side
    );
    let bound = sidak_bound(0.01, rows.len(), Some(fb.total.count()));
    let zmax = zcheck::max_abs_z(rows.iter().map(|r| r.max_z));
    let pass = zcheck::within(zmax, bound) && escaped == 0 && back_side == 0;
    println!(
        "max |z| over the runs {zmax:.2} against the Sidak bound {bound:.2}: {}",
        if pass { "PASS" } else { "FAIL" }
    );
    anyhow::ensure!(pass, "flux balance fails: light leaks or is lost");
    Ok(())
}
