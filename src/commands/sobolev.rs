//! `lumest sobolev`: the exact Sobolev solution at a list of distances.

use crate::io::format_number;
use crate::reference::Sobolev;
use clap::Args;
use rayon::prelude::*;

/// Physical parameters of the Sobolev problem.
#[derive(Args, Clone, Debug)]
pub struct SobolevParams {
    /// Distance from the source to plane 1 (m).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub h1: f64,
    /// Distance from the source to plane 2 (m).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub h2: f64,
    /// Reflectance of plane 1.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub rho1: f64,
    /// Reflectance of plane 2.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub rho2: f64,
    /// Intensity of the isotropic source (cd).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub intensity: f64,
}

impl SobolevParams {
    /// The validated reference problem.
    pub fn problem(&self) -> anyhow::Result<Sobolev> {
        Sobolev::new(self.h1, self.h2, self.rho1, self.rho2, self.intensity)
            .map_err(|e| anyhow::anyhow!("{e}"))
    }
}

/// Arguments of `lumest sobolev`.
#[derive(Args, Clone, Debug)]
pub struct SobolevArgs {
    #[command(flatten)]
    pub params: SobolevParams,
    /// Plane (1 or 2).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=2), allow_negative_numbers = true)]
    pub plane: u8,
    /// Horizontal distances (m): `a,b,c` or `start:stop:step`.
    #[arg(long, allow_hyphen_values = true)]
    pub r: String,
    /// Also print reflection orders 1..K.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub orders: u32,
}

/// Parse `a,b,c` or `start:stop:step` (stop included within rounding).
pub fn parse_list(s: &str) -> anyhow::Result<Vec<f64>> {
    let num = |t: &str| -> anyhow::Result<f64> {
        let x: f64 = t
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("`{t}` is not a number in list `{s}`"))?;
        anyhow::ensure!(x.is_finite(), "`{t}` is not finite in list `{s}`");
        Ok(x)
    };
    if s.contains(':') {
        let parts: Vec<&str> = s.split(':').collect();
        anyhow::ensure!(parts.len() == 3, "a range is `start:stop:step`, got `{s}`");
        let (a, b, h) = (num(parts[0])?, num(parts[1])?, num(parts[2])?);
        anyhow::ensure!(
            h > 0.0 && b >= a,
            "range `{s}` needs step > 0 and stop >= start"
        );
        let n = ((b - a) / h * (1.0 + 1e-12) + 1e-9).floor() as usize;
        anyhow::ensure!(n < 10_000_000, "range `{s}` has too many values");
        Ok((0..=n).map(|k| a + h * k as f64).collect())
    } else {
        s.split(',').map(num).collect()
    }
}

/// Run the command: CSV on standard output.
pub fn sobolev(args: &SobolevArgs) -> anyhow::Result<()> {
    let problem = args.params.problem()?;
    let rs = parse_list(&args.r).map_err(|e| anyhow::anyhow!("--r: {e}"))?;
    for &r in &rs {
        anyhow::ensure!(r >= 0.0, "--r: distances must be >= 0, got {r}");
    }
    let rows: Vec<String> = rs
        .par_iter()
        .map(|&r| {
            let v = problem.illuminance(args.plane, r);
            let mut cells = vec![
                format_number(r),
                format_number(v.e),
                format_number(v.e_direct),
                format_number(v.e_reflected),
            ];
            for n in 1..=args.orders {
                cells.push(format_number(problem.order(args.plane, r, n)));
            }
            cells.join(",")
        })
        .collect();
    let mut out = String::from("r,E,E_direct,E_reflected");
    for n in 1..=args.orders {
        out.push_str(&format!(",E_order{n}"));
    }
    out.push('\n');
    for row in rows {
        out.push_str(&row);
        out.push('\n');
    }
    crate::io::write_atomic("-", out.as_bytes())?;
    Ok(())
}
