//! Spherical-harmonic coefficient files: CSV `k,m,a,b`.

use super::csvio::{self, InputError};
use crate::math::sph_harm::ShCoeff;
use std::path::Path;

/// Display name of a path as csvio prints it (`-` is standard input).
fn display_name(path: &str) -> String {
    if path == "-" {
        "<stdin>".to_string()
    } else {
        path.to_string()
    }
}

/// Parse a non-negative integer index from a cell.
fn index_cell(cell: &str, file: &str, line: u64, field: &str) -> Result<usize, InputError> {
    cell.parse::<usize>().map_err(|_| InputError::Field {
        file: display_name(file),
        line,
        field: field.to_string(),
        message: format!("`{cell}` is not a non-negative integer"),
    })
}

/// Read SH coefficients from a CSV file with the header columns `k,m,a,b`
/// (any order; other columns ignored, each name once; lines starting with
/// `#` before the header are comments; `-` is standard input). `a`, `b` in local units.
///
/// Errors name the file, the line and the field: a missing column, a
/// non-integer `k` or `m`, `k > max_degree`, `m > k`, a non-finite `a` or
/// `b`, `b != 0` at `m = 0`, a repeated `(k, m)`, or an empty table.
pub fn read_coefficients(path: &Path, max_degree: usize) -> Result<Vec<ShCoeff>, InputError> {
    let name = path.to_string_lossy();
    let name = name.as_ref();
    let table = csvio::read_table(name)?;
    let cols = csvio::columns(&table.headers, &["k", "m", "a", "b"], name)?;
    csvio::unique_columns(&table, name)?;
    let field_err = |line: u64, field: &str, message: String| InputError::Field {
        file: display_name(name),
        line,
        field: field.to_string(),
        message,
    };
    let mut out = Vec::with_capacity(table.rows.len());
    let mut seen = std::collections::HashMap::new();
    for (row, &line) in table.rows.iter().zip(&table.lines) {
        let cell = |i: usize| row.get(cols[i]).map_or("", String::as_str);
        let k = index_cell(cell(0), name, line, "k")?;
        let m = index_cell(cell(1), name, line, "m")?;
        let a = csvio::number(cell(2), name, line, "a")?;
        let b = csvio::number(cell(3), name, line, "b")?;
        if k > max_degree {
            let msg = format!("degree {k} exceeds the supported maximum {max_degree}");
            return Err(field_err(line, "k", msg));
        }
        if m > k {
            let msg = format!("order m = {m} exceeds degree k = {k} (need m <= k)");
            return Err(field_err(line, "m", msg));
        }
        if m == 0 && b != 0.0 {
            let msg = format!("b = {b} must be 0 at m = 0 (sin(0 phi) = 0)");
            return Err(field_err(line, "b", msg));
        }
        if let Some(first) = seen.insert((k, m), line) {
            let msg = format!("(k, m) = ({k}, {m}) repeats line {first}");
            return Err(field_err(line, "k,m", msg));
        }
        out.push(ShCoeff { k, m, a, b });
    }
    if out.is_empty() {
        return Err(InputError::File {
            file: display_name(name),
            message: "no coefficients in the file".into(),
        });
    }
    Ok(out)
}

/// Write coefficients as CSV `k,m,a,b` with shortest round-trip numbers
/// (reading the file back gives the same `f64`s), atomically (temporary
/// file, then rename); `-` writes to standard output.
pub fn write_coefficients(path: &Path, coeffs: &[ShCoeff]) -> std::io::Result<()> {
    let mut text = String::from("k,m,a,b\n");
    for c in coeffs {
        text.push_str(&format!(
            "{},{},{},{}\n",
            c.k,
            c.m,
            csvio::format_number(c.a),
            csvio::format_number(c.b)
        ));
    }
    csvio::write_atomic(&path.to_string_lossy(), text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The geometry's degree limit (`geometry::sh::MAX_DEGREE`).
    const MAX: usize = 100;

    fn c(k: usize, m: usize, a: f64, b: f64) -> ShCoeff {
        ShCoeff { k, m, a, b }
    }

    #[test]
    fn coefficient_files_round_trip_and_report_bad_lines() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("coeffs.csv");
        // Numbers without a short decimal form, tiny and huge ones.
        let coeffs = vec![
            c(0, 0, 1.0, 0.0),
            c(1, 0, 1.0 / 3.0, 0.0),
            c(1, 1, -0.1, 2.0f64.sqrt()),
            c(3, 2, 1e-300, -2.5e17),
            c(2, 2, std::f64::consts::PI, -0.0),
        ];
        write_coefficients(&path, &coeffs).unwrap();
        assert_eq!(read_coefficients(&path, MAX).unwrap(), coeffs);

        let bad = |text: &str| {
            let p = dir.path().join("bad.csv");
            std::fs::write(&p, text).unwrap();
            let e = read_coefficients(&p, MAX).unwrap_err().to_string();
            let name = p.to_string_lossy().into_owned();
            assert!(e.starts_with(&name), "{e}");
            e
        };
        let e = bad("k,m,a,b\n0,0,1,0\n1,x,0.1,0\n");
        assert!(
            e.contains(":3: field `m`: `x` is not a non-negative integer"),
            "{e}"
        );
        let e = bad("k,m,a,b\n0,0,1,0\n1,-1,0.1,0\n");
        assert!(e.contains(":3: field `m`"), "{e}");
        let e = bad("k,m,a,b\n0,0,1,0\n1,1,abc,0\n");
        assert!(e.contains(":3: field `a`: `abc` is not a number"), "{e}");
        let e = bad("k,m,a,b\n0,0,1,0\n1,1,0.1,inf\n");
        assert!(e.contains(":3: field `b`: `inf` is not finite"), "{e}");
        let e = bad("k,m,a,b\n0,0,1,0\n2,3,0.1,0\n");
        assert!(
            e.contains(":3: field `m`: order m = 3 exceeds degree k = 2"),
            "{e}"
        );
        let e = bad("k,m,a,b\n0,0,1,0.5\n");
        assert!(
            e.contains(":2: field `b`: b = 0.5 must be 0 at m = 0"),
            "{e}"
        );
        let e = bad("k,m,a,b\n0,0,1,0\n1,1,0.1,0\n1,1,0.2,0\n");
        assert!(
            e.contains(":4: field `k,m`: (k, m) = (1, 1) repeats line 3"),
            "{e}"
        );
        let e = bad("k,m,a,b\n101,0,1,0\n");
        assert!(e.contains(":2: field `k`: degree 101 exceeds"), "{e}");
        let e = bad("k,m,a\n0,0,1\n");
        assert!(e.contains("missing column `b`"), "{e}");
        let e = bad("0,0,1,0\n1,0,0.1,0\n");
        assert!(e.contains("missing column `k`"), "{e}");
        let e = bad("k,m,a,b\n");
        assert!(e.contains("no coefficients in the file"), "{e}");
        // Extra columns and any column order are fine.
        let p = dir.path().join("order.csv");
        std::fs::write(&p, "b,a,id,m,k\n0,1.5,x,0,0\n0.25,0,y,1,1\n").unwrap();
        assert_eq!(
            read_coefficients(&p, MAX).unwrap(),
            vec![c(0, 0, 1.5, 0.0), c(1, 1, 0.0, 0.25)]
        );
    }
}
