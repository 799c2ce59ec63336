//! `lumest validate stress`: a matrix of hard cases, one row per point.
//!
//! Each row is one point of one case: its estimate with standard error, a
//! reference (exact, or an independent Monte Carlo run), the z score of the
//! difference, the run's time and chains, the statistical checks of the
//! tally ([`crate::tally::Diagnostics`]) and a verdict.
//!
//! # The matrix
//!
//! | family | cases | reference |
//! |---|---|---|
//! | `sobolev` | `rho1 rho2` in {0.9, 0.99, 0.999} with `rho1 = rho2 = sqrt(rho1 rho2)`; `h1` in {0.5, 0.01, 0.001} m with `h2 = 1 - h1` (planes 1 m apart); points on plane 1 at `r` in {0, 1e-3, 100, 1e4} m, normal towards the source | exact ([`Sobolev`]) |
//! | `integrating-sphere` | [`sphere_case`] with `rho = 0.999`, radius 1 m, 100 cd off centre, 6 wall points | closed form |
//! | `near-wall` | [`box_room`] (`rho = 0.8`): points 1e-6 m from a wall (facing the room, and with the normal along the wall), 1e-6 m from each face of a floor corner and of a ceiling corner (diagonal normals), 1e-6 m in front of the glossy partition, and one floor point | backward estimator ([`crate::backward::run`]), independent streams |
//! | `near-source` | the Sobolev planes with the source 1e-6 m above plane 1 (`h1 = 1e-6`, `h2 = 1 - h1`, `rho = 0.5`): floor points at `r` in {0, 1e-6, 1e-3, 1, 10} m, ceiling points at {0, 1} m | exact |
//! | `scaled` | Sobolev case A (`h1 = h2 = 0.5`, `rho = 0.5`, 1 cd) with every length times `s` in {1e-3, 1e4}: `E_s(s r) = E_1(r) / s^2`; a plain 5 x 4 x 3 m room with a desk and a point light, times `s` in {1e-3, 1e4} | exact; the unscaled room (another seed) times `1/s^2` |
//!
//! # Verdicts
//!
//! With `m` rows that have a z score, each row's bound is the Sidak bound at
//! family-wise rate `alpha` over `m` tests (Student t with the row's batches
//! minus one degrees of freedom; for a Monte Carlo reference the fewer
//! batches of the two):
//!
//! - `pass`: every number finite and `|z|` within the bound;
//! - `flagged`: the diagnostics of the estimate (or of a Monte Carlo
//!   reference, marked `ref:`) fail a check (`R`, `VOV`, `FOM`, `tail`,
//!   `batches`), so the error bar is not to be trusted and `|z|` is not
//!   tested; the flag says which check;
//! - `FAIL`: a number that is not finite (estimate, error, reference or
//!   z), an error or a panic while the case is built or run, or `|z|` beyond
//!   the bound on a row the diagnostics do not flag.
//!
//! The z score carries a rounding allowance in quadrature: `3 eps` times
//! the two direct parts (closed forms of a few operations; 1e12 lx next to
//! the source), plus `1e-12` of the Sobolev reflected part (its stated
//! accuracy); a row whose allowance matters says so in its note.
//!
//! # Known failures and their remedy
//!
//! Two kinds of rows are wrong with the plain local estimate, because the
//! contributions that carry the mean are never sampled; the batch
//! statistics cannot see what never happened, and only the `sparse` check,
//! which looks at where the scores come from, can:
//!
//! - **a wall in view at 1e-6 m** (`near-wall`, the point with its normal
//!   along the wall and the corners): the wall's part of the illuminance
//!   comes from collisions within a few `h` of the point (kernel
//!   `h cos / d^4`); none lands there, so about a third of `E` is missing,
//!   with a steady error bar. **Remedy**: the near/far split
//!   (`--near-radius`, [`crate::estimator::Receivers::with_near_field`]): the
//!   matrix runs every near-wall point again with `R = 0.2 m` (case label
//!   `near-radius=0.2`); those rows pass, and the plain rows they fix are
//!   marked `explained`.
//! - **far field** (`sobolev`, `r = 1e4`, `rho1 rho2 >= 0.9`): the
//!   reflected illuminance at `r = 1e4 H` is carried by light that has
//!   spread out between the planes over thousands of plane spacings (at
//!   `rho1 rho2 = 0.999` the exact `E` is 1.8 times the far-field asymptote
//!   `(h_1 + rho_2 h_2) / ((1 - rho_1 rho_2) r^3)`). The plain local
//!   estimate is 95-100 % low with a small, steady error bar: no chain
//!   lands near the point. The `sparse` check
//!   ([`crate::tally::Diagnostics`]) flags exactly that (fewer than 10
//!   collisions scored from the ball that holds 99.5 % of the point's
//!   view), so these rows are `flagged`, not silent. **Remedy**:
//!   `--near-radius auto` (case label `near-radius=auto`, points at
//!   `r >= 100`), whose recursive near part joins its paths' vertices to
//!   the batch's collisions around the source
//!   ([`crate::estimator::Receivers::with_near_field`]); those rows agree
//!   with the exact values. (Before the recursion, a split with `R = 5 m`
//!   was 5-47 % low and backward paths alone 44 % low at 0.999.)
//!
//! The quick subset keeps the far-field rows of its two Sobolev cases (they
//! must come out `flagged` with `sparse`: a regression guard for the check)
//! and leaves the near-wall plain rows to the full matrix.
//!
//! # Budget
//!
//! A case runs for `--time-per-case` seconds (default 2; soft: at least 32
//! batches), or `--chains N` chains (paths per point for the backward
//! estimator). `--quick` runs a subset, one or two cases per family, each
//! with its own fixed number of chains (bit-identical for any thread count),
//! in a few seconds.

use super::cases::{box_room, sphere_case};
use super::validate::{Checkpoint, convergence, write_report};
use crate::estimator::{Receiver, Receivers};
use crate::geometry::Plane;
use crate::geometry::shapes::AaBox;
use crate::io::csvio::to_csv;
use crate::io::{format_number, write_atomic};
use crate::light::Light;
use crate::material::Material;
use crate::reference::Sobolev;
use crate::run::{RunConfig, RunResult, Stop, run};
use crate::scene::{Scene, Sides, SurfaceSpec};
use crate::tally::{figure_of_merit, sidak_bound};
use clap::Args;
use glam::DVec3;
use std::f64::consts::PI;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `lumest validate stress`.
#[derive(Args, Clone, Debug)]
pub struct StressArgs {
    /// Run only the quick subset, each case with its own fixed number of chains.
    #[arg(long)]
    pub quick: bool,
    /// Wall-clock time per case [s] (default 2; with `--quick`, fixed chains instead).
    #[arg(long = "time-per-case")]
    pub time_per_case: Option<f64>,
    /// Chains per case instead of a time (paths per point for the backward estimator).
    #[arg(long, conflicts_with = "time_per_case")]
    pub chains: Option<u64>,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Folder for `stress.csv`, `stress_summary.csv` and the convergence tables and plots.
    #[arg(long, default_value = "validation_report")]
    pub report: PathBuf,
    /// Family-wise false-alarm rate of the z test over all rows.
    #[arg(long, default_value_t = 0.01)]
    pub alpha: f64,
}

/// How long each case runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Wall-clock seconds per Monte Carlo run (soft: at least 32 batches).
    Time(f64),
    /// The same number of chains for every run (paths per point for the
    /// backward estimator), rounded up to whole batches.
    Chains(u64),
    /// Each case's own fixed number of chains, a fraction of a second on two
    /// cores (the quick subset's budget).
    Tuned,
}

/// Options of a stress run (the library form of [`StressArgs`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StressOptions {
    /// Only the quick subset.
    pub quick: bool,
    /// How long each case runs.
    pub budget: Budget,
    /// Seed of every run (the independent reference runs derive their own).
    pub seed: u64,
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Family-wise false-alarm rate of the z test over all rows.
    pub alpha: f64,
}

impl StressOptions {
    /// The options of `args`, checked.
    pub fn from_args(a: &StressArgs) -> anyhow::Result<Self> {
        if let Some(t) = a.time_per_case {
            anyhow::ensure!(
                t.is_finite() && t > 0.0,
                "--time-per-case must be a positive number of seconds, got {t}"
            );
        }
        if let Some(c) = a.chains {
            anyhow::ensure!(c > 0, "--chains must be positive");
        }
        anyhow::ensure!(
            a.alpha > 0.0 && a.alpha < 1.0,
            "--alpha must lie in (0, 1), got {}",
            a.alpha
        );
        let budget = match (a.chains, a.time_per_case, a.quick) {
            (Some(c), _, _) => Budget::Chains(c),
            (None, Some(t), _) => Budget::Time(t),
            (None, None, true) => Budget::Tuned,
            (None, None, false) => Budget::Time(2.0),
        };
        Ok(Self {
            quick: a.quick,
            budget,
            seed: a.seed,
            threads: a.threads,
            alpha: a.alpha,
        })
    }

    /// Run configuration for one run with seed `seed`; `tuned` chains under
    /// [`Budget::Tuned`].
    fn config(&self, seed: u64, tuned: u64) -> RunConfig {
        let chains = match self.budget {
            Budget::Time(_) => None,
            Budget::Chains(c) => Some(c),
            Budget::Tuned => Some(tuned),
        };
        let stop = Stop {
            time: match self.budget {
                Budget::Time(t) => Some(t),
                _ => None,
            },
            chains,
            ..Stop::default()
        };
        RunConfig {
            seed,
            threads: self.threads,
            stop,
            // A chain budget gets at least 128 batches (the default would give
            // 32): at 32 batches the VOV check flags about 4 % of perfectly
            // normal tallies, at 128 practically none.
            batch_size: chains.map(|c| (c / 128).clamp(1, 1 << 16)),
            // The plain local estimate; the remedy rows turn the split on.
            near_auto: false,
            ..RunConfig::default()
        }
    }
}

/// Outcome of one row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Finite, and `|z|` within the Sidak bound.
    Pass,
    /// The diagnostics flag the estimate or its Monte Carlo reference.
    Flagged,
    /// Not finite, an error, or `|z|` beyond the bound and not flagged.
    Fail,
    /// A known failure of the plain local estimate (the singular kernel:
    /// a wall in view at 1e-6 m, or the far field), whose remedy row, the
    /// same point with the near/far split (`--near-radius`), passes.
    Explained,
}

impl Verdict {
    /// `pass`, `flagged` or `FAIL`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Flagged => "flagged",
            Verdict::Fail => "FAIL",
            Verdict::Explained => "explained",
        }
    }
}

/// One row of the stress matrix: one point of one case.
#[derive(Clone, Debug)]
pub struct StressRow {
    /// Family (`sobolev`, `integrating-sphere`, `near-wall`, `near-source`, `scaled`).
    pub family: String,
    /// Case within the family, e.g. `rho1rho2=0.999 h1=0.001`.
    pub case: String,
    /// The point, e.g. `plane 1 r=100`.
    pub point: String,
    /// Estimated illuminance `E` [lx] (exact first order plus the estimate of the rest).
    pub estimate: f64,
    /// Standard error of `estimate` [lx].
    pub std_error: f64,
    /// Exact first order (direct illuminance) included in `estimate` [lx].
    pub direct: f64,
    /// Exact value [lx], when known.
    pub exact: Option<f64>,
    /// What the estimate is compared with: `exact`, `backward` or
    /// `unscaled run / s^2`; empty (like the other reference fields) for a
    /// case that failed before its run gave a number.
    pub reference_kind: String,
    /// The value compared with [lx] (the exact value, or the other estimate).
    pub reference: Option<f64>,
    /// Standard error of a Monte Carlo reference [lx] (0 for an exact one).
    pub reference_std_error: f64,
    /// `(estimate - reference) / |reference|` [1].
    pub rel_err: Option<f64>,
    /// `(estimate - reference) / sqrt(std_error^2 + reference_std_error^2 + allowance^2)`
    /// with the rounding allowance of the module doc [1].
    pub z: Option<f64>,
    /// Wall time of the run that produced the estimate [s].
    pub time: f64,
    /// Chains of that run.
    pub chains: u64,
    /// Batches of that run (the fewer of the two with a Monte Carlo reference).
    pub batches: u64,
    /// `ok`, or the failed checks of the estimate's tally (and `ref:` those of a Monte Carlo reference).
    pub flag: String,
    /// Sidak bound the row's `|z|` is tested against (0 until judged).
    pub bound: f64,
    /// The verdict.
    pub verdict: Verdict,
    /// Explanation: why a row fails or is flagged, errors, remarks.
    pub note: String,
}

/// Every row with its verdict, and the convergence tables of the runs with exact references.
#[derive(Clone, Debug)]
pub struct StressReport {
    /// The rows, judged.
    pub rows: Vec<StressRow>,
    /// `(file stem, title, checkpoints)` of each run against exact values.
    pub convergence: Vec<(String, String, Vec<Checkpoint>)>,
    /// Wall time of the whole matrix [s].
    pub wall: f64,
}

/// A point of a case: its label, its receiver and its exact value [lx], if
/// known, optionally split into the direct part and the rest.
struct Point {
    label: String,
    receiver: Receiver,
    exact: Option<f64>,
    parts: Option<(f64, f64)>,
}

/// The reference of a row before it is judged.
#[derive(Clone)]
struct Reference {
    kind: &'static str,
    value: f64,
    /// The exact value as (direct, reflected) [lx]: the difference is then
    /// taken part by part, so that a huge direct term (a point next to the
    /// source) does not swamp the reflected one in rounding.
    parts: Option<(f64, f64)>,
    std_error: f64,
    exact: bool,
    batches: u64,
    flag: Option<String>,
}

/// The rows and convergence tables gathered so far, and the options.
struct Ctx<'a> {
    opts: &'a StressOptions,
    rows: Vec<StressRow>,
    convergence: Vec<(String, String, Vec<Checkpoint>)>,
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
            flag: String::new(),
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
            // `--near-radius auto`
            cfg.near = (0.0, NEAR_PATHS);
            cfg.near_auto = true;
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
                flag: None,
            };
            self.rows.push(make_row(family, case, &p.label, &res, j, r));
        }
        Ok(())
    }
}

/// Build a row from point `j` of run `res` and its reference `r`.
fn make_row(
    family: &str,
    case: &str,
    label: &str,
    res: &RunResult,
    j: usize,
    r: Reference,
) -> StressRow {
    let w = &res.tallies.indirect[j];
    let estimate = res.direct[j] + w.mean();
    let se = w.std_error();
    let mut flag = res.tallies.diagnostics(j, res.direct[j]).flag();
    if let Some(rf) = r.flag.filter(|f| f != "ok") {
        flag = if flag == "ok" {
            format!("ref:{rf}")
        } else {
            format!("{flag};ref:{rf}")
        };
    }
    let diff = match r.parts {
        Some((d, refl)) => (res.direct[j] - d) + (w.mean() - refl),
        None => estimate - r.value,
    };
    let rel_err = if r.value != 0.0 {
        diff / r.value.abs()
    } else if diff == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    // Rounding allowance: the direct parts are closed forms of a few
    // operations, each good to eps/2, so two of them differ by at most about
    // 6 eps |d| (next to a source that dwarfs the Monte Carlo error); the
    // Sobolev reflected part is good to about 1e-13 (its module doc).
    let eps = 3.0 * f64::EPSILON;
    let allowance = match r.parts {
        Some((d, refl)) => eps * (res.direct[j].abs() + d.abs()) + 1e-12 * refl.abs(),
        None => eps * (estimate.abs() + r.value.abs()),
    };
    let mc = se.hypot(r.std_error);
    let note = if allowance > 0.1 * mc {
        format!(
            "z includes a rounding allowance of {} lx",
            format_number(allowance)
        )
    } else {
        String::new()
    };
    let s = mc.hypot(allowance);
    let z = if s > 0.0 {
        diff / s
    } else if diff == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    StressRow {
        family: family.into(),
        case: case.into(),
        point: label.into(),
        estimate,
        std_error: se,
        direct: res.direct[j],
        exact: r.exact.then_some(r.value),
        reference_kind: r.kind.to_string(),
        reference: Some(r.value),
        reference_std_error: r.std_error,
        rel_err: Some(rel_err),
        z: Some(z),
        time: res.wall,
        chains: res.chains,
        batches: res.tallies.batches().min(r.batches),
        flag,
        bound: 0.0,
        verdict: Verdict::Pass,
        note,
    }
}

/// The two Sobolev planes of `s` as a scene: plane 1 `z = 0` (normal +z),
/// the source at `z = h1`, plane 2 `z = h1 + h2` (normal -z).
fn planes_scene(s: &Sobolev) -> Scene {
    Scene::from_parts(
        vec![
            (
                "plane 1".into(),
                Plane::new(DVec3::ZERO, DVec3::Z),
                Material::Lambertian { rho: s.rho1 },
            ),
            (
                "plane 2".into(),
                Plane::new(DVec3::new(0.0, 0.0, s.h1 + s.h2), -DVec3::Z),
                Material::Lambertian { rho: s.rho2 },
            ),
        ],
        vec![Light::Point {
            p: DVec3::new(0.0, 0.0, s.h1),
            i: s.intensity,
        }],
    )
    .expect("a valid programmatic scene")
}

/// Point `k` on plane `plane` of `s` at horizontal distance `r` [m] from the
/// foot of the source (azimuth by the golden angle), facing the source side.
fn plane_point(s: &Sobolev, plane: u8, r: f64, k: usize) -> (DVec3, DVec3) {
    let phi = PI * (3.0 - 5f64.sqrt()) * (k as f64 + 0.5);
    let (z, n) = if plane == 1 {
        (0.0, DVec3::Z)
    } else {
        (s.h1 + s.h2, -DVec3::Z)
    };
    (DVec3::new(r * phi.cos(), r * phi.sin(), z), n)
}

/// Points of `s` at `(plane, r)` with exact values `E(plane, r / scale) / scale^2`
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
            let (p, n) = plane_point(s, plane, r, k);
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

/// The plain test room of the `scaled` family, every length times `s`: a
/// 5 x 4 x 3 box with inward normals (walls 0.8, floor 0.4, ceiling 0.7), a
/// solid desk (0.4) and one 300 cd point light; five points (floor, desk
/// top, wall, ceiling, and the floor in the desk's shadow: reflected light only).
/// Run [`plain_room`] scaled by `s` with `seed` (32768 chains in the quick subset).
fn run_plain_room(
    ctx: &Ctx,
    s: f64,
    seed: u64,
) -> anyhow::Result<(RunResult, Vec<(String, Receiver)>)> {
    let (scene, pts) = plain_room(s);
    let rec: Vec<Receiver> = pts.iter().map(|p| p.1).collect();
    let receivers = Receivers::from_receivers(&scene, &rec).map_err(|e| anyhow::anyhow!("{e}"))?;
    let res = run(
        &scene,
        &receivers,
        &ctx.opts.config(seed, 32768),
        &mut |_| true,
    );
    Ok((res, pts))
}

fn plain_room(s: f64) -> (Scene, Vec<(String, Receiver)>) {
    let wall = Material::Lambertian { rho: 0.8 };
    let faces = [
        wall,
        wall,
        wall,
        wall,
        Material::Lambertian { rho: 0.4 },
        Material::Lambertian { rho: 0.7 },
    ];
    let scene = Scene::build(
        vec![
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
        ],
        vec![Light::Point {
            p: DVec3::new(1.5, 2.0, 2.7) * s,
            i: 300.0,
        }],
    )
    .expect("a valid programmatic scene");
    let points = [
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
    .collect();
    (scene, points)
}

/// The `sobolev` family.
fn family_sobolev(ctx: &mut Ctx) {
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
            // ln(0.1)/ln(rho) + 1/(1 - rho) collisions).
            let tuned = if prod == 0.999 { 2048 } else { 65536 };
            let case = format!("rho1rho2={prod} h1={h1}");
            ctx.guarded("sobolev", &case, |ctx| {
                let rho = prod.sqrt();
                let s = Sobolev::new(h1, 1.0 - h1, rho, rho, 1.0)?;
                // r = 1e4 is a known failure of the plain estimate that the
                // `sparse` check must flag (module doc).
                let at: Vec<(u8, f64)> = radii.iter().map(|&r| (1, r)).collect();
                let points = sobolev_points(&s, &s, 1.0, &at)?;
                ctx.against_exact("sobolev", &case, &planes_scene(&s), &points, tuned, false)?;
                // The remedy for the far field: `--near-radius auto` (module
                // doc); in the quick subset for `rho1 rho2 = 0.9` only.
                if !ctx.opts.quick || prod == 0.9 {
                    let far: Vec<(u8, f64)> = at.iter().copied().filter(|p| p.1 >= 100.0).collect();
                    let points = sobolev_points(&s, &s, 1.0, &far)?;
                    let case = format!("{case} {NEAR_FAR_LABEL}");
                    ctx.against_exact("sobolev", &case, &planes_scene(&s), &points, tuned, true)?;
                }
                Ok(())
            });
        }
    }
}

/// The `integrating-sphere` family.
fn family_sphere(ctx: &mut Ctx) {
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
        ctx.against_exact("integrating-sphere", &case, &c.scene, &points, 2048, false)
    });
}

/// The `near-wall` family: local against backward estimation.
fn family_near_wall(ctx: &mut Ctx) {
    let rho = 0.8;
    let case = format!("box room rho={rho}");
    ctx.guarded("near-wall", &case, |ctx| {
        let scene = box_room(rho);
        let d = 1e-6;
        let diag = DVec3::ONE.normalize();
        // (label, point, normal, in the quick subset): the points with a
        // wall in view at 1e-6 m are known failures (module doc), left out
        // of the quick subset.
        let all = [
            (
                "wall x=0 +1e-6, n=+x (facing the room)",
                DVec3::new(d, 2.5, 1.5),
                DVec3::X,
                true,
            ),
            (
                "wall x=0 +1e-6, n=+z (along the wall)",
                DVec3::new(d, 2.5, 1.5),
                DVec3::Z,
                false,
            ),
            (
                "floor corner +1e-6, n=(1,1,1)/sqrt3",
                DVec3::splat(d),
                diag,
                false,
            ),
            (
                "ceiling corner -1e-6, n=-(1,1,1)/sqrt3",
                DVec3::new(5.0, 4.0, 3.0) - DVec3::splat(d),
                -diag,
                false,
            ),
            (
                "partition x=3.5 +1e-6, n=+x",
                DVec3::new(3.5 + d, 1.0, 1.0),
                DVec3::X,
                true,
            ),
            (
                "floor (4, 3, 0), n=+z",
                DVec3::new(4.0, 3.0, 0.0),
                DVec3::Z,
                true,
            ),
        ];
        let pts: Vec<(&str, DVec3, DVec3)> = all
            .iter()
            .filter(|p| p.3 || !ctx.opts.quick)
            .map(|&(l, p, n, _)| (l, p, n))
            .collect();
        let rec: Vec<Receiver> = pts
            .iter()
            .map(|&(_, p, n)| Receiver::illuminance(p, n))
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
        for (j, (label, _, _)) in pts.iter().enumerate() {
            let w = &back.tallies.indirect[j];
            let r = Reference {
                kind: "backward",
                parts: None,
                value: back.direct[j] + w.mean(),
                std_error: w.std_error(),
                exact: false,
                batches: back.tallies.batches(),
                flag: Some(back.tallies.diagnostics(j, back.direct[j]).flag()),
            };
            let t = format!("backward: {:.3} s, {} paths", back.wall, back.chains);
            for (res, c) in [
                (&local, case.clone()),
                (&split, format!("{case} {NEAR_WALL_LABEL}")),
            ] {
                let mut row = make_row("near-wall", &c, label, res, j, r.clone());
                row.note = if row.note.is_empty() {
                    t.clone()
                } else {
                    format!("{}; {t}", row.note)
                };
                ctx.rows.push(row);
            }
        }
        Ok(())
    });
}

/// The `near-source` family: the source 1e-6 m above plane 1.
fn family_near_source(ctx: &mut Ctx) {
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
            &planes_scene(&s),
            &points,
            65536,
            false,
        )
    });
}

/// The `scaled` family: Sobolev case A and the plain room, lengths times `s`.
fn family_scaled(ctx: &mut Ctx) {
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
            ctx.against_exact("scaled", &case, &planes_scene(&s), &points, 65536, false)
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
                let w = &unscaled.tallies.indirect[j];
                let r = Reference {
                    kind: "unscaled run / s^2",
                    parts: None,
                    value: (unscaled.direct[j] + w.mean()) * k,
                    std_error: w.std_error() * k,
                    exact: false,
                    batches: unscaled.tallies.batches(),
                    flag: Some(unscaled.tallies.diagnostics(j, unscaled.direct[j]).flag()),
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

/// Radius of the near/far split for the near-wall rows [m].
const WALL_RADIUS: f64 = 0.2;
/// Backward paths per point and batch of the near part.
const NEAR_PATHS: u32 = 16;
const NEAR_FAR_LABEL: &str = "near-radius=auto";
const NEAR_WALL_LABEL: &str = "near-radius=0.2";

/// A plain row whose failure the near/far split explains: the same family
/// and point in a case carrying a near-radius label, and that row passes.
fn explain(rows: &mut [StressRow]) {
    let remedies: Vec<(String, String, String, Verdict)> = rows
        .iter()
        .filter(|r| r.case.contains("near-radius="))
        .map(|r| (r.family.clone(), r.case.clone(), r.point.clone(), r.verdict))
        .collect();
    for r in rows.iter_mut() {
        if r.verdict != Verdict::Fail || r.case.contains("near-radius=") || r.batches == 0 {
            continue;
        }
        let fixed = remedies.iter().find(|m| {
            m.0 == r.family && m.2 == r.point && m.1.starts_with(&r.case) && m.3 != Verdict::Fail
        });
        if let Some(m) = fixed {
            r.verdict = Verdict::Explained;
            r.note = format!(
                "the plain local estimate misses light from surfaces very close to the point \
                 (singular kernel): see case `{}` ({}); {}",
                m.1,
                m.3.as_str(),
                r.note
            );
        }
    }
}

/// Judge every row: finiteness, the diagnostics, then `|z|` against the
/// Sidak bound over the rows that have a z score.
fn judge(rows: &mut [StressRow], alpha: f64) {
    let m = rows.iter().filter(|r| r.z.is_some()).count();
    for r in rows.iter_mut() {
        if r.verdict == Verdict::Fail && r.batches == 0 {
            continue; // an error or a panic, already explained
        }
        let mut bad: Vec<&str> = Vec::new();
        for (name, v) in [
            ("estimate", Some(r.estimate)),
            ("std_error", Some(r.std_error)),
            ("exact", r.exact),
            ("reference", r.reference),
            ("reference std_error", Some(r.reference_std_error)),
            ("z", r.z),
        ] {
            if v.is_some_and(|x| !x.is_finite()) {
                bad.push(name);
            }
        }
        r.bound = sidak_bound(alpha, m, Some(r.batches.max(2)));
        let note = |r: &StressRow, s: String| {
            if r.note.is_empty() {
                s
            } else {
                format!("{s}; {}", r.note)
            }
        };
        if !bad.is_empty() {
            r.verdict = Verdict::Fail;
            r.note = note(r, format!("not finite: {}", bad.join(", ")));
        } else if r.verdict == Verdict::Fail {
            // Already failed by a check of its own (the note says which).
        } else if r.flag != "ok" {
            r.verdict = Verdict::Flagged;
            let z = r.z.map_or(String::new(), |z| {
                if z.abs() > r.bound {
                    format!(" (|z| = {:.2} beyond the bound {:.2})", z.abs(), r.bound)
                } else {
                    format!(" (|z| = {:.2} within the bound)", z.abs())
                }
            });
            r.note = note(r, format!("diagnostics: {}{z}", r.flag));
        } else if let Some(z) = r.z {
            if z.abs() <= r.bound {
                r.verdict = Verdict::Pass;
            } else {
                r.verdict = Verdict::Fail;
                r.note = note(
                    r,
                    format!(
                        "|z| = {:.2} beyond the Sidak bound {:.2} and not flagged",
                        z.abs(),
                        r.bound
                    ),
                );
            }
        } else {
            r.verdict = Verdict::Pass;
        }
    }
}

/// Run the stress matrix (or its quick subset) and judge every row. Never
/// fails: errors and panics of a case become FAIL rows naming it.
pub fn stress_rows(opts: &StressOptions) -> StressReport {
    let t0 = Instant::now();
    let mut ctx = Ctx {
        opts,
        rows: Vec::new(),
        convergence: Vec::new(),
    };
    family_sobolev(&mut ctx);
    family_sphere(&mut ctx);
    family_near_wall(&mut ctx);
    family_near_source(&mut ctx);
    family_scaled(&mut ctx);
    let mut rows = ctx.rows;
    judge(&mut rows, opts.alpha);
    explain(&mut rows);
    StressReport {
        rows,
        convergence: ctx.convergence,
        wall: t0.elapsed().as_secs_f64(),
    }
}

/// Format an optional number for a table cell (empty when absent).
fn cell(x: Option<f64>) -> String {
    x.map_or(String::new(), format_number)
}

/// The rows as CSV text (the columns of `stress.csv`).
pub fn stress_csv(rows: &[StressRow]) -> Vec<u8> {
    let headers: Vec<String> = [
        "family",
        "case",
        "point",
        "estimate",
        "std_error",
        "direct",
        "exact",
        "reference_kind",
        "reference",
        "reference_std_error",
        "rel_err",
        "z",
        "sidak_bound",
        "time_s",
        "chains",
        "batches",
        "flag",
        "verdict",
        "note",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.family.clone(),
                r.case.clone(),
                r.point.clone(),
                format_number(r.estimate),
                format_number(r.std_error),
                format_number(r.direct),
                cell(r.exact),
                r.reference_kind.clone(),
                cell(r.reference),
                format_number(r.reference_std_error),
                cell(r.rel_err),
                cell(r.z),
                format_number(r.bound),
                format_number(r.time),
                r.chains.to_string(),
                r.batches.to_string(),
                r.flag.clone(),
                r.verdict.as_str().to_string(),
                r.note.clone(),
            ]
        })
        .collect();
    to_csv(&headers, &cells)
}

/// Per family: rows, verdict counts, RMS and largest `|rel_err|` against
/// exact values, RMS relative standard error `R`, run time [s] (each run once)
/// and `FOM = 1 / (R_rms^2 T)` [1/s].
pub fn summary_csv(rows: &[StressRow]) -> Vec<u8> {
    let headers: Vec<String> = [
        "family",
        "rows",
        "pass",
        "flagged",
        "FAIL",
        "rms_rel_err_exact",
        "max_rel_err_exact",
        "rms_rel_stderr",
        "time_s",
        "fom",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut families: Vec<&str> = Vec::new();
    for r in rows {
        if !families.contains(&r.family.as_str()) {
            families.push(&r.family);
        }
    }
    let cells = families
        .iter()
        .map(|f| {
            let fr: Vec<&StressRow> = rows.iter().filter(|r| r.family == *f).collect();
            let count = |v: Verdict| fr.iter().filter(|r| r.verdict == v).count().to_string();
            let errs: Vec<f64> = fr
                .iter()
                .filter(|r| r.exact.is_some())
                .filter_map(|r| r.rel_err.map(f64::abs))
                .collect();
            let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
            let rr: Vec<f64> = fr
                .iter()
                .filter(|r| r.batches > 0)
                .map(|r| crate::tally::relative_error(r.estimate, r.std_error))
                .collect();
            let mut cases: Vec<(&str, f64)> =
                fr.iter().map(|r| (r.case.as_str(), r.time)).collect();
            cases.dedup_by(|a, b| a.0 == b.0);
            let time: f64 = cases.iter().map(|c| c.1).sum();
            let r_rms = rms(&rr);
            vec![
                f.to_string(),
                fr.len().to_string(),
                count(Verdict::Pass),
                count(Verdict::Flagged),
                count(Verdict::Fail),
                if errs.is_empty() {
                    String::new()
                } else {
                    format_number(rms(&errs))
                },
                errs.iter()
                    .copied()
                    .reduce(f64::max)
                    .map_or(String::new(), format_number),
                format_number(r_rms),
                format_number(time),
                format_number(figure_of_merit(r_rms, time)),
            ]
        })
        .collect::<Vec<_>>();
    to_csv(&headers, &cells)
}

/// Print the table of rows.
pub fn print_rows(rows: &[StressRow]) {
    println!(
        "{:<19} {:<24} {:<42} {:>11} {:>9} {:>11} {:>10} {:>8} {:>7} {:>9} {:<14} {:<7}",
        "family",
        "case",
        "point",
        "estimate",
        "stderr",
        "reference",
        "rel_err",
        "z",
        "time_s",
        "chains",
        "flag",
        "verdict"
    );
    let opt = |x: Option<f64>, p: usize| x.map_or("-".to_string(), |v| format!("{v:.p$e}"));
    for r in rows {
        println!(
            "{:<19} {:<24} {:<42} {:>11.4e} {:>9.2e} {:>11} {:>10} {:>8} {:>7.2} {:>9} {:<14} {:<7}",
            r.family,
            r.case,
            r.point,
            r.estimate,
            r.std_error,
            opt(r.reference, 4),
            opt(r.rel_err, 2),
            r.z.map_or("-".to_string(), |z| format!("{z:.2}")),
            r.time,
            r.chains,
            r.flag,
            r.verdict.as_str()
        );
    }
    let notes: Vec<&StressRow> = rows.iter().filter(|r| !r.note.is_empty()).collect();
    if !notes.is_empty() {
        println!("notes:");
        for r in notes {
            println!(
                "  {} / {} / {}: {}: {}",
                r.family,
                r.case,
                r.point,
                r.verdict.as_str(),
                r.note
            );
        }
    }
}

/// `lumest validate stress`: run the matrix, print the table, write
/// `stress.csv`, `stress_summary.csv` and the convergence tables and plots
/// of the runs against exact values. Fails only when a row is `FAIL`.
pub fn validate_stress(a: &StressArgs) -> anyhow::Result<()> {
    let opts = StressOptions::from_args(a)?;
    println!(
        "Stress matrix{}: {}, seed {}, alpha {}",
        if opts.quick { " (quick subset)" } else { "" },
        match opts.budget {
            Budget::Time(t) => format!("{t} s per case"),
            Budget::Chains(c) => format!("{c} chains per case"),
            Budget::Tuned => "fixed chains per case".to_string(),
        },
        opts.seed,
        opts.alpha
    );
    let report = stress_rows(&opts);
    print_rows(&report.rows);
    std::fs::create_dir_all(&a.report)
        .map_err(|e| anyhow::anyhow!("creating {}: {e}", a.report.display()))?;
    let path = a.report.join("stress.csv");
    write_atomic(&path.to_string_lossy(), &stress_csv(&report.rows))?;
    let spath = a.report.join("stress_summary.csv");
    let summary = summary_csv(&report.rows);
    write_atomic(&spath.to_string_lossy(), &summary)?;
    println!("per family:");
    print!("{}", String::from_utf8_lossy(&summary));
    for (stem, title, rows) in &report.convergence {
        if rows.len() >= 2 {
            write_report(&a.report, stem, rows, title)?;
        }
    }
    let count = |v: Verdict| report.rows.iter().filter(|r| r.verdict == v).count();
    let (pass, flagged, fail, explained) = (
        count(Verdict::Pass),
        count(Verdict::Flagged),
        count(Verdict::Fail),
        count(Verdict::Explained),
    );
    eprintln!("lumest: wrote {} and {}", path.display(), spath.display());
    println!(
        "{} rows: {pass} pass, {flagged} flagged, {explained} explained (plain local estimate, fixed by the near/far split), {fail} FAIL; {:.1} s",
        report.rows.len(),
        report.wall
    );
    let failed: Vec<String> = report
        .rows
        .iter()
        .filter(|r| r.verdict == Verdict::Fail)
        .map(|r| format!("{} / {} / {}", r.family, r.case, r.point))
        .collect();
    anyhow::ensure!(
        failed.is_empty(),
        "stress matrix: {fail} row(s) FAIL: {}",
        failed.join("; ")
    );
    Ok(())
}
