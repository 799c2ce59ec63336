//! Chi-square tests of the tabulated sphere density
//! (`lumest::sampling::sphere_table`), the environment map's importance
//! sampler: samples binned on a grid in `(cos theta, phi)` that is not
//! aligned with the table's cells, against the density integrated exactly
//! over each bin (it is constant per solid angle in each cell, and solid
//! angle is `d(cos theta) d(phi)`). A table 2 % wrong must be rejected.

mod common;

use lumest::sampling::Philox4x32;
use lumest::sampling::sphere_table::SphereTable;
use std::f64::consts::PI;

/// A sky-like table: a gradient, a bright sun of a few cells, a dark ground
/// row band, in `rows x cols` cells.
fn sky(rows: usize, cols: usize) -> Vec<f64> {
    (0..rows * cols)
        .map(|k| {
            let (i, j) = (k / cols, k % cols);
            let theta = PI * (i as f64 + 0.5) / rows as f64;
            let phi = 2.0 * PI * (j as f64 + 0.5) / cols as f64;
            if theta > 0.75 * PI {
                0.0 // dark ground
            } else if (5..7).contains(&i) && (10..13).contains(&j) {
                400.0 // the sun
            } else {
                1.0 + 0.5 * theta.cos() + 0.2 * (3.0 * phi).sin()
            }
        })
        .collect()
}

/// Expected probability of each bin of an `nb x mb` grid in
/// `(cos theta, phi)` under the table's values `f` (which may differ from
/// the sampled table's).
fn expected(t: &SphereTable, f: &[f64], nb: usize, mb: usize) -> Vec<f64> {
    let (rows, cols) = t.size();
    let dphi = 2.0 * PI / cols as f64;
    let total: f64 = (0..rows)
        .flat_map(|i| (0..cols).map(move |j| (i, j)))
        .map(|(i, j)| f[i * cols + j] * t.cell_solid_angle(i))
        .sum();
    let mut p = vec![0.0; nb * mb];
    for b in 0..nb {
        // Bins uniform in cos theta from 1 down to -1.
        let (b_hi, b_lo) = (
            1.0 - 2.0 * b as f64 / nb as f64,
            1.0 - 2.0 * (b + 1) as f64 / nb as f64,
        );
        for m in 0..mb {
            let (q0, q1) = (
                2.0 * PI * m as f64 / mb as f64,
                2.0 * PI * (m + 1) as f64 / mb as f64,
            );
            let mut s = 0.0;
            for i in 0..rows {
                let (c_hi, c_lo) = t.row_edges(i);
                let oc = (c_hi.min(b_hi) - c_lo.max(b_lo)).max(0.0);
                if oc == 0.0 {
                    continue;
                }
                for j in 0..cols {
                    let (p0, p1) = (j as f64 * dphi, (j + 1) as f64 * dphi);
                    let op = (p1.min(q1) - p0.max(q0)).max(0.0);
                    s += f[i * cols + j] * oc * op;
                }
            }
            p[b * mb + m] = s / total;
        }
    }
    p
}

fn histogram(t: &SphereTable, n: usize, nb: usize, mb: usize, seed: u64) -> Vec<f64> {
    let mut h = vec![0.0; nb * mb];
    let mut rng = Philox4x32::new(seed, 0);
    for _ in 0..n {
        let s = t.sample(rng.next_2d());
        assert!(s.pdf > 0.0);
        let b = (((1.0 - s.cos_theta) / 2.0 * nb as f64) as usize).min(nb - 1);
        let m = ((s.phi / (2.0 * PI) * mb as f64) as usize).min(mb - 1);
        h[b * mb + m] += 1.0;
    }
    h
}

#[test]
fn chi2_sphere_table_matches_its_density_and_rejects_a_2_percent_error() {
    let (rows, cols) = (24, 48);
    let f = sky(rows, cols);
    let t = SphereTable::new(f.clone(), rows, cols).unwrap();
    let (nb, mb) = (37, 53);
    let n = 2_000_000;
    let obs = histogram(&t, n, nb, mb, 9);
    let exp: Vec<f64> = expected(&t, &f, nb, mb)
        .iter()
        .map(|p| p * n as f64)
        .collect();
    let (p, stat, dof) = common::chi2_pvalue(&obs, &exp);
    // Three checks in this file share alpha = 1e-3 (Sidak).
    let alpha = 1.0 - (1.0 - 1e-3f64).powf(1.0 / 3.0);
    assert!(p > alpha, "chi2 = {stat:.1} on {dof} dof, p = {p:.3e}");
    // On a coarse grid (more power against smooth errors) the table passes,
    // and the same samples against a table whose upper hemisphere is 2 %
    // too bright fail.
    let (cb, cm) = (7, 9);
    let coarse = histogram(&t, n, cb, cm, 9);
    let exp_c: Vec<f64> = expected(&t, &f, cb, cm)
        .iter()
        .map(|p| p * n as f64)
        .collect();
    let (p_c, stat_c, dof_c) = common::chi2_pvalue(&coarse, &exp_c);
    assert!(
        p_c > alpha,
        "coarse: chi2 = {stat_c:.1} on {dof_c} dof, p = {p_c:.3e}"
    );
    let wrong: Vec<f64> = f
        .iter()
        .enumerate()
        .map(|(k, &v)| if k / cols < rows / 2 { 1.02 * v } else { v })
        .collect();
    let exp_w: Vec<f64> = expected(&t, &wrong, cb, cm)
        .iter()
        .map(|p| p * n as f64)
        .collect();
    let (p_w, stat_w, _) = common::chi2_pvalue(&coarse, &exp_w);
    assert!(
        p_w < 1e-9,
        "a 2 % wrong table passed: chi2 = {stat_w:.1}, p = {p_w:.3e}"
    );
}

/// Within a single cell the samples are uniform by solid angle: a one-cell
/// band table against the uniform sphere, on a fine grid.
#[test]
fn chi2_uniform_table_is_the_uniform_sphere() {
    let t = SphereTable::new(vec![3.0; 2], 1, 2).unwrap();
    let (nb, mb) = (20, 30);
    let n = 600_000;
    let obs = histogram(&t, n, nb, mb, 4);
    let exp = vec![n as f64 / (nb * mb) as f64; nb * mb];
    let (p, stat, dof) = common::chi2_pvalue(&obs, &exp);
    let alpha = 1.0 - (1.0 - 1e-3f64).powf(1.0 / 3.0);
    assert!(p > alpha, "chi2 = {stat:.1} on {dof} dof, p = {p:.3e}");
    assert!((t.integral() - 3.0 * 4.0 * PI).abs() < 1e-12);
}
