//! The families of the stress matrix: each builds its cases from the
//! validation cases' scenes, runs them and adds their rows.

use super::options::{MIN_CHAINS, StressOptions};
use super::row::{Reference, StressRow, make_row};
use super::verdict::Verdict;
use crate::cases::box_room::{BoxRoom, box_room};
use crate::cases::integrating_sphere::sphere_case;
use crate::cases::report::{Checkpoint, convergence};
use crate::cases::sobolev::{plane_point, sobolev_scene};
use crate::estimator::local::run;
use crate::estimator::{Receiver, Receivers};
use crate::io::format_number;
use crate::reference::Sobolev;
use crate::run::RunResult;
use crate::scene::Scene;
use glam::DVec3;
use std::f64::consts::PI;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

/// A point of a case: its label, its receiver and its exact value \[lx\], if
/// known, optionally split into the direct part and the rest.
struct Point {
    label: String,
    receiver: Receiver,
    exact: Option<f64>,
    parts: Option<(f64, f64)>,
}

/// The rows and convergence tables gathered so far, and the options.
pub(super) struct Ctx<'a> {
    pub(super) opts: &'a StressOptions,
    pub(super) rows: Vec<StressRow>,
    pub(super) convergence: Vec<(String, String, Vec<Checkpoint>)>,
}

impl Ctx<'_> {
    /// Run `f` for case `case` of `family`; an error or a panic becomes one FAIL row.
    fn guarded(
        &mut self,
        family: &str,
        case: &str,
        f: impl FnOnce(&mut Self) -> anyhow::Result<()>,
    ) {
        let t0 = Instant::now();
        eprintln!("lumest: stress: {family}: {case}");
        let res = catch_unwind(AssertUnwindSafe(|| f(self)));
        let message = match res {
            Ok(Ok(())) => return,
            Ok(Err(e)) => format!("error: {e:#}"),
            Err(p) => {
                let what = p
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| p.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "(no message)".into());
                format!("panic: {what}")
            }
        };
        eprintln!("lumest: stress: {family}: {case}: {message}");
        self.rows.push(StressRow {
            family: family.into(),
            case: case.into(),
            point: String::new(),
            estimate: f64::NAN,
            std_error: f64::NAN,
            direct: f64::NAN,
            exact: None,
            reference_kind: String::new(),
            reference: None,
            reference_std_error: 0.0,
            rel_err: None,
            z: None,
            time: t0.elapsed().as_secs_f64(),
            chains: 0,
            batches: 0,
            batch_chains: 0,
            flag: String::new(),
            checks: (None, None),
            expected: None,
            bound: 0.0,
            verdict: Verdict::Fail,
            note: message,
        });
    }

    /// Run the local estimator on `points` of `scene` against their exact
    /// values (with checkpoints for the convergence report) and add the
    /// rows; with `split`, the near/far split of `--near-radius auto`.
    fn against_exact(
        &mut self,
        family: &str,
        case: &str,
        scene: &Scene,
        points: &[Point],
        tuned: u64,
        split: bool,
    ) -> anyhow::Result<()> {
        let rec: Vec<Receiver> = points.iter().map(|p| p.receiver).collect();
        let receivers =
            Receivers::from_receivers(scene, &rec).map_err(|e| anyhow::anyhow!("{e}"))?;
        let exact: Vec<f64> = points
            .iter()
            .map(|p| p.exact.expect("exact values"))
            .collect();
        if let Some(j) = exact.iter().position(|e| !e.is_finite()) {
            anyhow::bail!(
                "exact value at {} is not finite: {}",
                points[j].label,
                exact[j]
            );
        }
        let mut cfg = self.opts.config(self.opts.seed, tuned);
        if split {
            split_auto(&mut cfg);
        }
        let all = 0..exact.len();
        let (res, tables) = convergence(
            scene,
            &receivers,
            &exact,
            std::slice::from_ref(&all),
            &cfg,
            true,
        );
        let stem = format!("stress_{family}_{case}")
            .replace([' ', '='], "_")
            .replace(['(', ')', ','], "");
        let title = format!("stress {family}, {case}: relative error of E against run time");
        if let Some(rows) = tables.into_iter().next() {
            self.convergence.push((stem, title, rows));
        }
        for (j, p) in points.iter().enumerate() {
            let r = Reference {
                kind: "exact",
                value: exact[j],
                parts: p.parts,
                std_error: 0.0,
                exact: true,
                batches: res.tallies.batches(),
                checks: None,
            };
            self.rows.push(make_row(family, case, &p.label, &res, j, r));
        }
        Ok(())
    }
}

/// Points of `s` at `(plane, r)` ([`plane_point`], point `k` at the
/// azimuth `(k + 1/2)` times the golden angle) with exact values `E(plane, r / scale) / scale^2`
/// of `exact_of` (the unscaled problem; `scale = 1` for no scaling).
fn sobolev_points(
    s: &Sobolev,
    exact_of: &Sobolev,
    scale: f64,
    at: &[(u8, f64)],
) -> anyhow::Result<Vec<Point>> {
    at.iter()
        .enumerate()
        .map(|(k, &(plane, r))| {
            let phi = PI * (3.0 - 5f64.sqrt()) * (k as f64 + 0.5);
            let (p, n) = plane_point(s, plane, r, phi);
            let v = exact_of.illuminance(plane, r / scale);
            let k = 1.0 / (scale * scale);
            Ok(Point {
                label: format!("plane {plane} r={}", format_number(r)),
                receiver: Receiver::illuminance(p, n),
                exact: Some(v.e * k),
                parts: Some((v.e_direct * k, v.e_reflected * k)),
            })
        })
        .collect()
}

/// The near/far split of `--near-radius auto` on `cfg`, with
/// [`NEAR_PATHS`] paths per point.
fn split_auto(cfg: &mut crate::run::RunConfig) {
    cfg.near = (0.0, NEAR_PATHS);
    cfg.near_auto = true;
}

/// Run the plain room ([`BoxRoom::plain`]) scaled by `s` with `seed`
/// (32768 chains in the quick subset) at its points ([`plain_room_points`]),
/// with the near/far split of `--near-radius auto`, as users run it: the
/// floor point in the desk's shadow lies 0.1 m from the desk's side and 2.9 m
/// from the light, where the plain estimate is not to be trusted (the
/// `near` check), and what is tested here is the scaling, not that.
fn run_plain_room(
    ctx: &Ctx,
    s: f64,
    seed: u64,
) -> anyhow::Result<(RunResult, Vec<(String, Receiver)>)> {
    let scene = BoxRoom::plain(s).scene();
    let pts = plain_room_points(s);
    let rec: Vec<Receiver> = pts.iter().map(|p| p.1).collect();
    let receivers = Receivers::from_receivers(&scene, &rec).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut cfg = ctx.opts.config(seed, 32768);
    split_auto(&mut cfg);
    let res = run(&scene, &receivers, &cfg, &mut |_| true);
    Ok((res, pts))
}

/// The five points of the `scaled` family in the plain room, every length
/// times `s`: floor, desk top, wall, ceiling, and the floor in the desk's
/// shadow (reflected light only).
fn plain_room_points(s: f64) -> Vec<(String, Receiver)> {
    [
        ("floor", DVec3::new(4.0, 3.0, 0.0), DVec3::Z),
        ("desk top", DVec3::new(1.8, 1.4, 0.75), DVec3::Z),
        ("wall x=5", DVec3::new(5.0, 2.0, 1.5), -DVec3::X),
        ("ceiling", DVec3::new(2.5, 2.0, 3.0), -DVec3::Z),
        (
            "floor in the desk's shadow",
            DVec3::new(1.6, 0.9, 0.0),
            DVec3::Z,
        ),
    ]
    .into_iter()
    .map(|(l, p, n)| (l.to_string(), Receiver::illuminance(p * s, n)))
    .collect()
}

/// The `sobolev` family.
pub(super) fn family_sobolev(ctx: &mut Ctx) {
    let products: [f64; 3] = [0.9, 0.99, 0.999];
    let heights = [0.5, 0.01, 0.001];
    let radii = [0.0, 1e-3, 100.0, 1e4];
    for prod in products {
        for h1 in heights {
            let quick = (prod == 0.999 && h1 == 0.001) || (prod == 0.9 && h1 == 0.5);
            if ctx.opts.quick && !quick {
                continue;
            }
            // Chains per case in the quick subset (chain length about
            // ln(0.1)/ln(rho) + 1/(1 - rho) collisions): at 0.999 the
            // fewest allowed, 32 batches of 256.
            let tuned = if prod == 0.999 { MIN_CHAINS } else { 65536 };
            let case = format!("rho1rho2={prod} h1={h1}");
            ctx.guarded("sobolev", &case, |ctx| {
                let rho = prod.sqrt();
                let s = Sobolev::new(h1, 1.0 - h1, rho, rho, 1.0)?;
                // r = 1e4 is a known failure of the plain estimate that the
                // `sparse` check must flag (module doc).
                let at: Vec<(u8, f64)> = radii.iter().map(|&r| (1, r)).collect();
                let points = sobolev_points(&s, &s, 1.0, &at)?;
                ctx.against_exact("sobolev", &case, &sobolev_scene(&s), &points, tuned, false)?;
                // The remedy for the far field: `--near-radius auto` (module
                // doc); in the quick subset for `rho1 rho2 = 0.9` only.
                if !ctx.opts.quick || prod == 0.9 {
                    let far: Vec<(u8, f64)> = at.iter().copied().filter(|p| p.1 >= 100.0).collect();
                    let points = sobolev_points(&s, &s, 1.0, &far)?;
                    let case = format!("{case} {NEAR_FAR_LABEL}");
                    ctx.against_exact("sobolev", &case, &sobolev_scene(&s), &points, tuned, true)?;
                }
                Ok(())
            });
        }
    }
}

/// The `integrating-sphere` family.
pub(super) fn family_sphere(ctx: &mut Ctx) {
    let rho = 0.999;
    let case = format!("rho={rho} R=1");
    ctx.guarded("integrating-sphere", &case, |ctx| {
        let c = sphere_case(rho, 1.0, DVec3::new(0.3, -0.2, 0.45), 6, false);
        // Exact: the direct part plus the uniform indirect part
        // `integrating_sphere_indirect(rho, 4 pi I, R)` (in `c.exact`).
        let points: Vec<Point> = c
            .receivers
            .iter()
            .zip(&c.exact)
            .enumerate()
            .map(|(k, (r, &e))| Point {
                label: format!("wall point {k}"),
                receiver: *r,
                exact: Some(e),
                parts: None,
            })
            .collect();
        ctx.against_exact(
            "integrating-sphere",
            &case,
            &c.scene,
            &points,
            MIN_CHAINS,
            false,
        )
    });
}

/// The `near-wall` family: local against backward estimation.
pub(super) fn family_near_wall(ctx: &mut Ctx) {
    let rho = 0.8;
    let case = format!("box room rho={rho}");
    ctx.guarded("near-wall", &case, |ctx| {
        let scene = box_room(rho);
        let d = 1e-6;
        let diag = DVec3::ONE.normalize();
        // (label, point, normal, a wall in view within `WALL_RADIUS`): the
        // points with a wall in view at 1e-6 m are known failures of the
        // plain estimate (module doc); only at those points does the split
        // change anything (elsewhere no surface in view lies within the
        // radius, and the split run is the plain run bit for bit), so only
        // those get a split row. The quick subset runs every point.
        let pts = [
            (
                "wall x=0 +1e-6, n=+x (facing the room)",
                DVec3::new(d, 2.5, 1.5),
                DVec3::X,
                false,
            ),
            (
                "wall x=0 +1e-6, n=+z (along the wall)",
                DVec3::new(d, 2.5, 1.5),
                DVec3::Z,
                true,
            ),
            (
                "floor corner +1e-6, n=(1,1,1)/sqrt3",
                DVec3::splat(d),
                diag,
                true,
            ),
            (
                "ceiling corner -1e-6, n=-(1,1,1)/sqrt3",
                DVec3::new(5.0, 4.0, 3.0) - DVec3::splat(d),
                -diag,
                true,
            ),
            (
                "partition x=3.5 +1e-6, n=+x",
                DVec3::new(3.5 + d, 1.0, 1.0),
                DVec3::X,
                false,
            ),
            (
                "floor (4, 3, 0), n=+z",
                DVec3::new(4.0, 3.0, 0.0),
                DVec3::Z,
                false,
            ),
        ];
        let rec: Vec<Receiver> = pts
            .iter()
            .map(|&(_, p, n, _)| Receiver::illuminance(p, n))
            .collect();
        let receivers =
            Receivers::from_receivers(&scene, &rec).map_err(|e| anyhow::anyhow!("{e}"))?;
        let cfg = ctx.opts.config(ctx.opts.seed, 65536);
        let local = run(&scene, &receivers, &cfg, &mut |_| true);
        let mut near_cfg = cfg.clone();
        near_cfg.near = (WALL_RADIUS, NEAR_PATHS);
        let split = run(&scene, &receivers, &near_cfg, &mut |_| true);
        let mut bcfg = ctx.opts.config(ctx.opts.seed, 8192);
        // The backward default (about 2^16 paths per batch) would make the
        // 32 batches a timed run always completes take several seconds here.
        bcfg.batch_size = bcfg.batch_size.or(Some(512));
        let back = crate::backward::run(&scene, &receivers, &bcfg, &mut |_| true);
        for (j, &(label, _, _, wall_in_view)) in pts.iter().enumerate() {
            let w = &back.tallies.estimated[j];
            let r = Reference {
                kind: "backward",
                parts: None,
                value: back.direct[j] + w.mean(),
                std_error: w.std_error(),
                exact: false,
                batches: back.tallies.batches(),
                checks: Some(back.tallies.diagnostics(j, back.direct[j])),
            };
            let t = format!("backward: {:.3} s, {} paths", back.wall, back.chains);
            let mut runs = vec![(&local, case.clone())];
            if wall_in_view {
                runs.push((&split, format!("{case} {NEAR_WALL_LABEL}")));
            }
            for (res, c) in runs {
                let mut row = make_row("near-wall", &c, label, res, j, r.clone());
                row.note = if row.note.is_empty() {
                    t.clone()
                } else {
                    format!("{}; {t}", row.note)
                };
                // The split must change the estimate where a wall is in view
                // (a split run equal to the plain one bit for bit did not split).
                let same = split.tallies.estimated[j].mean().to_bits()
                    == local.tallies.estimated[j].mean().to_bits();
                if wall_in_view && same && !std::ptr::eq(res, &local) {
                    row.verdict = Verdict::Fail;
                    row.note = format!(
                        "the split run equals the plain run bit for bit; {}",
                        row.note
                    );
                }
                ctx.rows.push(row);
            }
        }
        Ok(())
    });
}

/// The `near-source` family: the source 1e-6 m above plane 1.
pub(super) fn family_near_source(ctx: &mut Ctx) {
    let h1 = 1e-6;
    let case = format!("h1={} h2=1-h1 rho=0.5", format_number(h1));
    ctx.guarded("near-source", &case, |ctx| {
        let s = Sobolev::new(h1, 1.0 - h1, 0.5, 0.5, 1.0)?;
        let at = [
            (1, 0.0),
            (1, 1e-6),
            (1, 1e-3),
            (1, 1.0),
            (1, 10.0),
            (2, 0.0),
            (2, 1.0),
        ];
        let points = sobolev_points(&s, &s, 1.0, &at)?;
        ctx.against_exact(
            "near-source",
            &case,
            &sobolev_scene(&s),
            &points,
            65536,
            false,
        )
    });
}

/// The `scaled` family: Sobolev case A and the plain room, lengths times `s`.
pub(super) fn family_scaled(ctx: &mut Ctx) {
    let scales = [1e-3, 1e4];
    for sc in scales {
        let case = format!("sobolev A s={}", format_number(sc));
        ctx.guarded("scaled", &case, |ctx| {
            let unit = Sobolev::new(0.5, 0.5, 0.5, 0.5, 1.0)?;
            let s = Sobolev::new(0.5 * sc, 0.5 * sc, 0.5, 0.5, 1.0)?;
            let at: Vec<(u8, f64)> = [(1, 0.0), (1, 0.5), (1, 2.0), (2, 0.0), (2, 1.0)]
                .iter()
                .map(|&(p, r)| (p, r * sc))
                .collect();
            let mut points = sobolev_points(&s, &unit, sc, &at)?;
            // The exact solution of the scaled problem itself must obey the scaling law.
            for (p, &(plane, r)) in points.iter_mut().zip(&at) {
                let e_scaled = s.illuminance(plane, r).e;
                let e = p.exact.expect("exact");
                let d = (e_scaled - e).abs() / e;
                if d > 1e-10 {
                    p.label
                        .push_str(&format!(" [Sobolev at scaled h differs by {d:.1e}]"));
                }
            }
            ctx.against_exact("scaled", &case, &sobolev_scene(&s), &points, 65536, false)
        });
    }
    // The room: the reference is the unscaled room with another seed.
    let seed_ref = ctx.opts.seed.wrapping_add(1_000_003);
    let mut reference: Option<(RunResult, Vec<String>)> = None;
    ctx.guarded("scaled", "room s=1 (reference run)", |ctx| {
        let (res, pts) = run_plain_room(ctx, 1.0, seed_ref)?;
        reference = Some((res, pts.into_iter().map(|p| p.0).collect()));
        Ok(())
    });
    let Some((unscaled, _)) = reference else {
        return;
    };
    for sc in scales {
        let case = format!("room s={}", format_number(sc));
        ctx.guarded("scaled", &case, |ctx| {
            let (res, pts) = run_plain_room(ctx, sc, ctx.opts.seed)?;
            let k = 1.0 / (sc * sc);
            for (j, (label, _)) in pts.iter().enumerate() {
                let w = &unscaled.tallies.estimated[j];
                let r = Reference {
                    kind: "unscaled run / s^2",
                    parts: None,
                    value: (unscaled.direct[j] + w.mean()) * k,
                    std_error: w.std_error() * k,
                    exact: false,
                    batches: unscaled.tallies.batches(),
                    checks: Some(unscaled.tallies.diagnostics(j, unscaled.direct[j])),
                };
                let mut row = make_row("scaled", &case, label, &res, j, r);
                // The direct part is exact in both: it must scale exactly (to rounding).
                let dd = (res.direct[j] - unscaled.direct[j] * k).abs();
                if dd > 1e-12 * (unscaled.direct[j] * k).abs() {
                    row.verdict = Verdict::Fail;
                    row.note = format!(
                        "direct part does not scale: {} against {}",
                        format_number(res.direct[j]),
                        format_number(unscaled.direct[j] * k)
                    );
                }
                ctx.rows.push(row);
            }
            Ok(())
        });
    }
}

/// Radius of the near/far split for the near-wall rows \[m\].
const WALL_RADIUS: f64 = 0.2;

/// Backward paths per point and batch of the near part.
const NEAR_PATHS: u32 = 16;

const NEAR_FAR_LABEL: &str = "near-radius=auto";

pub(super) const NEAR_WALL_LABEL: &str = "near-radius=0.2";
