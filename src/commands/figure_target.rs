//! `--figure-target GRID:FIGURE:H`: plan an illuminance run so that a grid
//! figure's 95 % interval is at most `+-H` wide (half-width `H`, in the
//! figure's unit).
//!
//! The run uses the two-stage rule of `--rel-error` ([`crate::run`]): a
//! pilot of 32 small batches on streams of its own, the grid figures of the
//! pilot (with their intervals, [`crate::tally::surface_figures`]), and a
//! fixed number of fresh batches `B = max(32, ceil(B_p (h_p / H)^2 q))`
//! where `h_p` is the pilot's half-width rescaled to the run's batch size
//! and `q` the 90 % upper confidence factor of the pilot's variance. With
//! several targets `h_p / H` is the largest ratio. Every interval of a
//! figure is a sum of standard errors times Student-t factors, so its width
//! falls like `1 / sqrt(chains)` and the plan holds; the t factors only
//! shrink as batches grow (the plan errs long). Only the fresh batches make
//! the result: it is that of a `--chains` run of the planned size.

use super::figures::{GridFigures, Group, grid_figures};
use crate::grid::Grid;
use crate::run::RunResult;
use crate::tally::surface_figures::Figure;

/// A figure of a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FigureKind {
    /// Area-weighted average \[lx\].
    EAvg,
    /// Minimum \[lx\].
    EMin,
    /// Maximum \[lx\].
    EMax,
    /// `E_min / E_avg`.
    U0,
    /// `E_min / E_max`.
    Ud,
}

impl FigureKind {
    /// The figure's name as the figures CSV writes it.
    pub fn name(self) -> &'static str {
        match self {
            FigureKind::EAvg => "E_avg",
            FigureKind::EMin => "E_min",
            FigureKind::EMax => "E_max",
            FigureKind::U0 => "U0",
            FigureKind::Ud => "Ud",
        }
    }

    fn of(self, g: &GridFigures) -> Option<&Figure> {
        let f = g.figures.as_ref()?;
        Some(match self {
            FigureKind::EAvg => &f.e_avg,
            FigureKind::EMin => &f.e_min,
            FigureKind::EMax => &f.e_max,
            FigureKind::U0 => &f.u0,
            FigureKind::Ud => &f.ud,
        })
    }
}

/// A precision target on one grid figure.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureTarget {
    /// The grid's name.
    pub grid: String,
    /// The figure.
    pub figure: FigureKind,
    /// Largest half-width of its 95 % interval (lx for illuminances, 1 for
    /// the uniformities).
    pub half_width: f64,
}

impl FigureTarget {
    /// Parse `GRID:FIGURE:H` (the grid's name may itself hold colons: the
    /// last two fields are the figure and the half-width).
    pub fn parse(s: &str) -> anyhow::Result<Self> {
        let mut parts = s.rsplitn(3, ':');
        let (h, fig, grid) = (parts.next(), parts.next(), parts.next());
        let (Some(h), Some(fig), Some(grid)) = (h, fig, grid) else {
            anyhow::bail!(
                "--figure-target `{s}`: expected GRID:FIGURE:HALF_WIDTH, like `work plane:U0:0.01`"
            );
        };
        let figure = match fig.trim() {
            "E_avg" | "Em" | "Eavg" => FigureKind::EAvg,
            "E_min" | "Emin" => FigureKind::EMin,
            "E_max" | "Emax" => FigureKind::EMax,
            "U0" => FigureKind::U0,
            "Ud" => FigureKind::Ud,
            other => anyhow::bail!(
                "--figure-target `{s}`: unknown figure `{other}` (one of E_avg, E_min, E_max, U0, Ud)"
            ),
        };
        let half_width: f64 = h.trim().parse().map_err(|_| {
            anyhow::anyhow!("--figure-target `{s}`: the half-width `{h}` is not a number")
        })?;
        anyhow::ensure!(
            half_width.is_finite() && half_width > 0.0,
            "--figure-target `{s}`: the half-width must be positive"
        );
        anyhow::ensure!(!grid.is_empty(), "--figure-target `{s}`: no grid name");
        Ok(Self {
            grid: grid.to_string(),
            figure,
            half_width,
        })
    }

    /// The half-width of this target's figure among `figs` (half the width
    /// of its 95 % interval; infinite when the figure or its interval is
    /// undefined or unbounded).
    pub fn achieved(&self, figs: &[GridFigures]) -> f64 {
        figs.iter()
            .find(|g| g.name == self.grid)
            .and_then(|g| self.figure.of(g))
            .map(|f| 0.5 * (f.ci95.1 - f.ci95.0))
            .filter(|h| h.is_finite())
            .unwrap_or(f64::INFINITY)
    }
}

/// The pilot's measure: the largest ratio of achieved half-width to target.
pub fn measure(r: &RunResult, groups: &[Group], grids: &[Grid], targets: &[FigureTarget]) -> f64 {
    let figs = grid_figures(r, groups, grids);
    worst_ratio(&figs, targets)
}

/// The largest `achieved / target` over the targets (NaN-free: an
/// undefined figure counts as infinite).
pub fn worst_ratio(figs: &[GridFigures], targets: &[FigureTarget]) -> f64 {
    targets
        .iter()
        .map(|t| t.achieved(figs) / t.half_width)
        .fold(0.0, |m, x| if x > m || x.is_nan() { x } else { m })
}

/// Summary lines: each target with the half-width reached.
pub fn summary_lines(figs: &[GridFigures], targets: &[FigureTarget]) -> Vec<String> {
    targets
        .iter()
        .map(|t| {
            let h = t.achieved(figs);
            format!(
                "--figure-target {}:{}:{}: 95 % interval half-width {:.4e}: {}",
                t.grid,
                t.figure.name(),
                t.half_width,
                h,
                if h <= t.half_width {
                    "target met".to_string()
                } else {
                    format!(
                        "target MISSED (by {:.1} %; the figure and its interval are still honest: \
                         run longer)",
                        100.0 * (h / t.half_width - 1.0)
                    )
                }
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_targets() {
        let t = FigureTarget::parse("work plane:U0:0.01").unwrap();
        assert_eq!(t.grid, "work plane");
        assert_eq!(t.figure, FigureKind::U0);
        assert_eq!(t.half_width, 0.01);
        let t = FigureTarget::parse("a:b:E_avg:2").unwrap();
        assert_eq!((t.grid.as_str(), t.figure), ("a:b", FigureKind::EAvg));
        for bad in [
            "U0:0.01",
            "g:U1:0.01",
            "g:U0:-1",
            "g:U0:x",
            ":U0:1",
            "g:U0:inf",
        ] {
            assert!(FigureTarget::parse(bad).is_err(), "{bad}");
        }
    }
}
