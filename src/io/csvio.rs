//! CSV point lists and result tables.
//!
//! Input: a header row naming at least `x,y,z,nx,ny,nz` (any order; other
//! columns such as `id` are carried through). Output: the input columns
//! followed by result columns. `-` stands for standard input / output.
//! Output files are written to a temporary file and renamed, so a reader
//! never sees half a table.

use glam::DVec3;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// A bad input file, naming the file, the line and the field.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("{file}: {message}")]
    File { file: String, message: String },
    #[error("{file}:{line}: field `{field}`: {message}")]
    Field {
        file: String,
        line: u64,
        field: String,
        message: String,
    },
    /// A row as a whole (its cell count), no one field.
    #[error("{file}:{line}: {message}")]
    Row {
        file: String,
        line: u64,
        message: String,
    },
}

/// A point list as read: raw columns (to carry through) and parsed geometry.
#[derive(Clone, Debug, Default)]
pub struct PointTable {
    /// Header names in file order.
    pub headers: Vec<String>,
    /// Raw cells of each row, in file order.
    pub rows: Vec<Vec<String>>,
    /// Line number of each row in the file (1-based).
    pub lines: Vec<u64>,
    /// Comment lines before the header (not rows).
    pub comment_lines: u64,
    /// Position \[m\] and unit normal of each row (normal normalised here).
    pub points: Vec<(DVec3, DVec3)>,
}

/// `path` as messages name it: `<stdin>` for `-`.
pub(crate) fn display_name(path: &str) -> String {
    if path == "-" {
        "<stdin>".to_string()
    } else {
        path.to_string()
    }
}

/// Read a CSV table from a file or `-` (standard input).
fn read_all(path: &str) -> Result<String, InputError> {
    let mut bytes = Vec::new();
    let res = if path == "-" {
        std::io::stdin().read_to_end(&mut bytes).map(|_| ())
    } else {
        std::fs::File::open(path)
            .and_then(|mut f| f.read_to_end(&mut bytes))
            .map(|_| ())
    };
    res.map_err(|e| InputError::File {
        file: display_name(path),
        message: format!("cannot read: {e}"),
    })?;
    utf8_text(bytes).map_err(|(line, column)| InputError::Row {
        file: display_name(path),
        line: line as u64,
        message: format!("the byte at column {column} is not UTF-8 text: save the file as UTF-8"),
    })
}

/// A file's bytes as text, or the line and column (1-based) of its first
/// byte that is not UTF-8.
pub(crate) fn utf8_text(bytes: Vec<u8>) -> Result<String, (usize, usize)> {
    String::from_utf8(bytes).map_err(|e| {
        let ok = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + ok.iter().filter(|&&b| b == b'\n').count();
        let column = 1 + ok.iter().rev().take_while(|&&b| b != b'\n').count();
        (line, column)
    })
}

/// A CSV table with named columns: headers, rows and row line numbers.
pub(crate) struct RawTable {
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
    pub lines: Vec<u64>,
    /// Comment lines (first character `#`) before the header.
    pub comment_lines: u64,
    /// Line number of the header (1-based).
    pub header_line: u64,
}

/// Whether a line (from `at` in `text`) is blank: nothing before its end.
fn blank_at(text: &str, at: usize) -> bool {
    let rest = &text[at..];
    rest.is_empty() || rest.starts_with('\n') || rest.starts_with("\r\n")
}

/// Read a CSV table with a header row.
///
/// Comments: lines whose first character is `#` are comments only before
/// the header (a file's preamble); after the header every non-blank line is
/// a row, so an id such as `#12` is data, never dropped. Blank lines are
/// skipped anywhere.
pub(crate) fn read_table(path: &str) -> Result<RawTable, InputError> {
    let file = display_name(path);
    let text = read_all(path)?;
    // The preamble: comment and blank lines before the header, after a
    // byte-order mark (which hid a first `#`: the comment became the
    // header).
    let bom = if text.starts_with('\u{feff}') {
        '\u{feff}'.len_utf8()
    } else {
        0
    };
    let (mut start, mut start_line, mut comment_lines) = (bom, 1u64, 0u64);
    while start < text.len() && (text[start..].starts_with('#') || blank_at(&text, start)) {
        comment_lines += u64::from(text[start..].starts_with('#'));
        match text[start..].find('\n') {
            Some(k) => {
                start += k + 1;
                start_line += 1;
            }
            None => start = text.len(),
        }
    }
    let body = &text[start..];
    // (Flexible: the cell counts are checked below, where a line of
    // spaces alone is skipped as blank.)
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .flexible(true)
        .from_reader(body.as_bytes());
    let headers: Vec<String> = rdr
        .headers()
        .map_err(|e| InputError::File {
            file: file.clone(),
            message: format!("bad header: {e}"),
        })?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    // Line numbers from byte offsets, counted on from the previous record
    // (records come in file order), so reading is linear in the file size.
    // A record's position is where the reader started on it, before the
    // blank lines it skipped, so those are stepped over here (the csv
    // crate's own line count is off the same way).
    let mut cursor = (0usize, start_line);
    let mut line_of = |byte: u64| -> u64 {
        let mut at = (byte as usize).min(body.len());
        let (from, from_line) = if at >= cursor.0 {
            cursor
        } else {
            (0, start_line)
        };
        #[cfg(test)]
        line_tests::SCANNED.with(|c| c.set(c.get() + (at - from) as u64));
        let mut line = from_line
            + body.as_bytes()[from..at]
                .iter()
                .filter(|&&c| c == b'\n')
                .count() as u64;
        cursor = (at, line);
        while at < body.len() && blank_at(body, at) {
            at += body[at..].find('\n').map_or(body.len() - at, |k| k + 1);
            line += 1;
        }
        line
    };
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, |p| line_of(p.byte()));
            // The csv crate's own text counts lines from after the
            // preamble and records from 0; the file's line is the prefix.
            let message = match e.kind() {
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => format!("{len} cells where the header has {expected_len} columns"),
                _ => e.to_string(),
            };
            InputError::Row {
                file: file.clone(),
                line,
                message,
            }
        })?;
        let line = rec.position().map_or(0, |p| line_of(p.byte()));
        if rec.len() != headers.len() {
            // A line of spaces (or tabs) alone is blank, as an empty one is.
            if rec.len() == 1 && rec[0].is_empty() {
                continue;
            }
            // An unclosed quote takes the rest of the file into one cell.
            let quote = rec.iter().any(|c| c.contains('\n'));
            return Err(InputError::Row {
                file: file.clone(),
                line,
                message: format!(
                    "{} cells where the header has {} columns{}",
                    rec.len(),
                    headers.len(),
                    if quote {
                        " (a cell runs over several lines: an unclosed `\"` quote?)"
                    } else {
                        ""
                    }
                ),
            });
        }
        lines.push(line);
        rows.push(rec.iter().map(str::to_string).collect());
    }
    Ok(RawTable {
        headers,
        rows,
        lines,
        comment_lines,
        header_line: start_line,
    })
}

/// Index of each wanted column, or an error naming the missing one.
pub(crate) fn columns(
    headers: &[String],
    wanted: &[&str],
    file: &str,
) -> Result<Vec<usize>, InputError> {
    wanted
        .iter()
        .map(|w| {
            headers
                .iter()
                .position(|h| h == w)
                .ok_or_else(|| InputError::File {
                    file: display_name(file),
                    message: format!(
                        "missing column `{w}` in the header (found: {}){}",
                        headers.join(","),
                        if headers.len() == 1 && headers[0].contains(';') {
                            "; the file seems to use `;` between columns: lumest reads comma-separated \
                             files with a decimal point (12.5, not 12,5)"
                        } else if headers.len() == 1 && headers[0].contains('\t') {
                            "; the file seems to use tabs between columns: lumest reads \
                             comma-separated files"
                        } else {
                            ""
                        }
                    ),
                })
        })
        .collect()
}

/// Refuse a header that names a column twice (after [`columns`] found the
/// wanted ones, so a file without a header reports the missing columns).
pub(crate) fn unique_columns(t: &RawTable, file: &str) -> Result<(), InputError> {
    let headers = &t.headers;
    for (k, h) in headers.iter().enumerate() {
        if let Some(j) = headers[..k].iter().position(|g| g == h) {
            return Err(InputError::Field {
                file: display_name(file),
                line: t.header_line,
                field: h.clone(),
                message: format!(
                    "column `{h}` appears twice in the header (columns {} and {}); \
                     every column name must be unique",
                    j + 1,
                    k + 1
                ),
            });
        }
    }
    Ok(())
}

/// Parse a finite number from a cell.
pub(crate) fn number(cell: &str, file: &str, line: u64, field: &str) -> Result<f64, InputError> {
    let err = |m: String| InputError::Field {
        file: display_name(file),
        line,
        field: field.to_string(),
        message: m,
    };
    let x: f64 = cell
        .parse()
        .map_err(|_| err(format!("`{cell}` is not a number")))?;
    if !x.is_finite() {
        return Err(err(format!("`{cell}` is not finite")));
    }
    Ok(x)
}

/// Read a point list (`x,y,z,nx,ny,nz` plus any other columns).
pub fn read_points(path: &str) -> Result<PointTable, InputError> {
    let (t, points) = read_rays(path, ["x", "y", "z", "nx", "ny", "nz"], "normal", "points")?;
    Ok(PointTable {
        headers: t.headers,
        rows: t.rows,
        lines: t.lines,
        comment_lines: t.comment_lines,
        points,
    })
}

/// Read a table of positions and directions from the six named columns;
/// the direction is normalised (a zero one is an error naming the line).
fn read_rays(
    path: &str,
    names: [&str; 6],
    what_dir: &str,
    what_rows: &str,
) -> Result<(RawTable, Vec<(DVec3, DVec3)>), InputError> {
    let t = read_table(path)?;
    let rays = rays_of(&t, path, names, what_dir, what_rows)?;
    Ok((t, rays))
}

/// The point table of raw `headers` and `rows` already read (and checked)
/// once, as a shard state keeps them: parsed as [`read_points`] parses a
/// file, so positions and normals are the same to the bit. `path` names
/// the table in messages; the line numbers count from a header on line 1.
pub fn points_of_rows(
    headers: &[String],
    rows: &[Vec<String>],
    path: &str,
) -> Result<PointTable, InputError> {
    let t = RawTable {
        headers: headers.to_vec(),
        rows: rows.to_vec(),
        lines: (2..).take(rows.len()).collect(),
        comment_lines: 0,
        header_line: 1,
    };
    let points = rays_of(
        &t,
        path,
        ["x", "y", "z", "nx", "ny", "nz"],
        "normal",
        "points",
    )?;
    Ok(PointTable {
        headers: t.headers,
        rows: t.rows,
        lines: t.lines,
        comment_lines: 0,
        points,
    })
}

/// The positions and unit directions of a table's rows from the six named
/// columns (a zero direction is an error naming the line).
fn rays_of(
    t: &RawTable,
    path: &str,
    names: [&str; 6],
    what_dir: &str,
    what_rows: &str,
) -> Result<Vec<(DVec3, DVec3)>, InputError> {
    let cols = columns(&t.headers, &names, path)?;
    unique_columns(t, path)?;
    let mut rays = Vec::with_capacity(t.rows.len());
    for (row, &line) in t.rows.iter().zip(&t.lines) {
        let mut v = [0.0; 6];
        for (k, (&c, name)) in cols.iter().zip(names).enumerate() {
            v[k] = number(row.get(c).map_or("", String::as_str), path, line, name)?;
            if k < 3 && v[k].abs() > crate::scene::MAX_COORD {
                return Err(InputError::Field {
                    file: display_name(path),
                    line,
                    field: name.to_string(),
                    message: format!(
                        "must lie within +-{:e} m (the geometry is resolved to 1e-11 of the \
                         coordinates; re-centre the scene and points), got {}",
                        crate::scene::MAX_COORD,
                        format_number(v[k])
                    ),
                });
            }
        }
        let Some(d) = crate::geometry::unit_direction(DVec3::new(v[3], v[4], v[5])) else {
            return Err(InputError::Field {
                file: display_name(path),
                line,
                field: names[3..].join(","),
                message: format!("the {what_dir} has zero length"),
            });
        };
        rays.push((DVec3::new(v[0], v[1], v[2]), d));
    }
    if rays.is_empty() {
        return Err(InputError::File {
            file: display_name(path),
            message: format!("no {what_rows} in the file"),
        });
    }
    Ok(rays)
}

/// A view list as read: raw columns and parsed observer rays.
#[derive(Clone, Debug, Default)]
pub struct ViewTable {
    /// Header names in file order.
    pub headers: Vec<String>,
    /// Raw cells of each row.
    pub rows: Vec<Vec<String>>,
    /// Line number of each row (1-based).
    pub lines: Vec<u64>,
    /// Comment lines before the header (not rows).
    pub comment_lines: u64,
    /// Observer position \[m\] and unit viewing direction of each row.
    pub views: Vec<(DVec3, DVec3)>,
}

/// Read a view list (`x,y,z,dx,dy,dz` plus any other columns): the observer
/// position and the direction it looks in (any non-zero length).
pub fn read_views(path: &str) -> Result<ViewTable, InputError> {
    let (t, views) = read_rays(
        path,
        ["x", "y", "z", "dx", "dy", "dz"],
        "view direction",
        "views",
    )?;
    Ok(ViewTable {
        headers: t.headers,
        rows: t.rows,
        lines: t.lines,
        comment_lines: t.comment_lines,
        views,
    })
}

/// Shortest round-trip text of `x`, in scientific notation when very small or large.
pub fn format_number(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        // `-0` as `0` (an empty sum of negative zeros printed `-0`).
        "0".to_string()
    } else if (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `x` with `decimals` decimals, in scientific notation (`decimals` digits
/// after the point) when so large or small that fixed notation would
/// print tens of digits or hide the value (`1.0000e50`, not 51 digits).
pub fn format_fixed(x: f64, decimals: usize) -> String {
    let a = x.abs();
    if !x.is_finite() || x == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{x:.decimals$}")
    } else {
        format!("{x:.decimals$e}")
    }
}

/// Write `contents` to `path` atomically (temporary file in the same folder,
/// then rename), or to standard output for `-`.
pub fn write_atomic(path: &str, contents: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |w| w.write_all(contents))
}

/// Write to `path` atomically through `fill`, which streams into a buffered
/// writer (temporary file in the same folder, then rename; nothing is left
/// behind when `fill` fails), or to standard output for `-`.
pub fn write_atomic_with<T>(
    path: &str,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<T>,
) -> std::io::Result<T> {
    if path == "-" {
        let mut out = std::io::BufWriter::new(std::io::stdout().lock());
        let v = fill(&mut out)?;
        out.flush()?;
        return Ok(v);
    }
    let target = through_links(Path::new(path));
    let tmp = temp_path(&target);
    let written = (|| {
        let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        let v = fill(&mut f)?;
        f.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        std::fs::rename(&tmp, &target)?;
        Ok(v)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// The file an output named `path` is written to: `path`, or where the
/// symbolic links it names lead (a link is kept and its file replaced:
/// renamed onto the link, the results replaced the link and left the file
/// it pointed to stale; a reviewer's find). At most 40 links are followed.
pub(crate) fn through_links(path: &Path) -> PathBuf {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        let is_link = std::fs::symlink_metadata(&p).is_ok_and(|m| m.file_type().is_symlink());
        if !is_link {
            break;
        }
        match std::fs::read_link(&p) {
            Ok(next) if next.is_absolute() => p = next,
            Ok(next) => {
                let dir = p.parent().map(Path::to_path_buf).unwrap_or_default();
                p = dir.join(next);
            }
            Err(_) => break,
        }
    }
    p
}

/// The temporary file next to `target` that an atomic write goes through.
pub(crate) fn temp_path(target: &Path) -> PathBuf {
    let dir = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = target
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    dir.join(format!(".{name}.{}.tmp", std::process::id()))
}

/// An output written to its temporary file and not yet renamed onto its
/// name: [`Staged::commit`] renames it; dropping it uncommitted removes the
/// temporary file. Several outputs staged first and committed after are
/// written all or none (short of a failure between renames).
#[derive(Debug)]
pub struct Staged {
    tmp: Option<PathBuf>,
    target: PathBuf,
}

impl Staged {
    /// Rename the temporary file onto the output's name.
    pub fn commit(mut self) -> std::io::Result<()> {
        match self.tmp.take() {
            Some(tmp) => std::fs::rename(&tmp, &self.target).inspect_err(|_| {
                let _ = std::fs::remove_file(&tmp);
            }),
            None => Ok(()),
        }
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Some(tmp) = self.tmp.take() {
            let _ = std::fs::remove_file(tmp);
        }
    }
}

/// Stream a CSV table to the temporary file of `path` (header, then each
/// row as it is produced) and return it staged, with the number of rows.
/// `-` is written to standard output at once (nothing to stage).
pub fn stage_csv(
    path: &str,
    headers: &[String],
    rows: impl IntoIterator<Item = Vec<String>>,
) -> std::io::Result<(Staged, usize)> {
    let write = |out: &mut dyn Write| -> std::io::Result<usize> {
        let mut w = csv::Writer::from_writer(out);
        w.write_record(headers)?;
        let mut n = 0;
        for r in rows {
            w.write_record(&r)?;
            n += 1;
        }
        w.flush()?;
        Ok(n)
    };
    if path == "-" {
        let n = write_atomic_with(path, write)?;
        let target = PathBuf::from(path);
        return Ok((Staged { tmp: None, target }, n));
    }
    let target = through_links(Path::new(path));
    let staged = Staged {
        tmp: Some(temp_path(&target)),
        target,
    };
    let tmp = staged.tmp.clone().expect("just set");
    let mut f = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
    let n = write(&mut f)?;
    f.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    Ok((staged, n))
}

/// Write `bytes` to the temporary file of `path` and return it staged
/// (see [`Staged`]); `-` is written to standard output at once.
pub fn stage_bytes(path: &str, bytes: &[u8]) -> std::io::Result<Staged> {
    let target = PathBuf::from(path);
    if path == "-" {
        write_atomic(path, bytes)?;
        return Ok(Staged { tmp: None, target });
    }
    let target = through_links(&target);
    let staged = Staged {
        tmp: Some(temp_path(&target)),
        target,
    };
    let tmp = staged.tmp.clone().expect("just set");
    let mut f = std::fs::File::create(&tmp)?;
    f.write_all(bytes)?;
    f.sync_all()?;
    Ok(staged)
}

/// Build CSV text from headers and rows of cells.
pub fn to_csv(headers: &[String], rows: &[Vec<String>]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(headers).expect("write to memory");
    for r in rows {
        w.write_record(r).expect("write to memory");
    }
    w.into_inner().expect("flush to memory")
}

#[cfg(test)]
mod line_tests {
    use super::read_table;

    thread_local! {
        /// Bytes the line numbering has scanned on this thread (an operation
        /// count: reading must stay linear in the file's size).
        pub(super) static SCANNED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
    }

    /// Reading points is linear (issue 15 item 2: the set-up grew with the
    /// square of the number of points when every record's line number was
    /// counted from the start of the file): the bytes scanned to number the
    /// lines stay within the file's size, at 1,000 and at 30,000 rows (the
    /// old count scanned 6.7 MB of a 13 kB file at 1,000 rows).
    #[test]
    fn line_numbering_scans_each_byte_once() {
        let dir = tempfile::tempdir().unwrap();
        for rows in [1_000, 30_000] {
            let p = dir.path().join(format!("p{rows}.csv"));
            let mut text = String::from("# a grid\nx,y,z,nx,ny,nz\n");
            for k in 0..rows {
                text += &format!("{},{},0,0,0,1\n", k % 173, k / 173);
                if k % 1000 == 999 {
                    text += "\n";
                }
            }
            std::fs::write(&p, &text).unwrap();
            SCANNED.with(|c| c.set(0));
            let t = read_table(p.to_str().unwrap()).unwrap();
            assert_eq!(t.rows.len(), rows);
            let scanned = SCANNED.with(|c| c.get());
            assert!(
                scanned <= text.len() as u64,
                "{rows} rows: scanned {scanned} bytes of a {}-byte file",
                text.len()
            );
        }
    }

    #[test]
    fn line_numbers_count_comment_lines() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, "# top\n\n# more\nid,y\na,2\n\n#b,4\n# c,6\n").unwrap();
        let t = read_table(p.to_str().unwrap()).unwrap();
        // Comments only before the header: `#b` and `# c` are rows.
        assert_eq!(t.comment_lines, 2);
        assert_eq!(t.lines, vec![5, 7, 8]);
        let ids: Vec<&str> = t.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(ids, ["a", "#b", "# c"]);
    }

    #[test]
    fn duplicated_column_names_are_rejected() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("dup.csv");
        std::fs::write(&p, "# note\nid,x,y,z,nx,ny,nz,x\na,0,0,0,0,0,1,5\n").unwrap();
        let e = super::read_points(p.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("dup.csv:2: field `x`") && e.contains("columns 2 and 8"),
            "{e}"
        );
        let p = dir.path().join("dupv.csv");
        std::fs::write(&p, "x,y,z,dx,dy,dz,dz\n0,0,0,0,0,1,1\n").unwrap();
        let e = super::read_views(p.to_str().unwrap())
            .unwrap_err()
            .to_string();
        assert!(e.contains("dupv.csv:1: field `dz`"), "{e}");
    }

    #[test]
    fn staged_outputs_are_written_all_or_none() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a.csv");
        let b = dir.path().join("b.csv");
        let h = vec!["x".to_string()];
        let (sa, n) = super::stage_csv(a.to_str().unwrap(), &h, vec![vec!["1".into()]]).unwrap();
        assert_eq!(n, 1);
        assert!(!a.exists(), "staged output visible before commit");
        // The second output fails (its folder is gone): the first is dropped too.
        let bad = dir.path().join("gone").join("b.csv");
        assert!(super::stage_csv(bad.to_str().unwrap(), &h, vec![]).is_err());
        drop(sa);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        let (sa, _) = super::stage_csv(a.to_str().unwrap(), &h, vec![vec!["1".into()]]).unwrap();
        let (sb, _) = super::stage_csv(b.to_str().unwrap(), &h, vec![vec!["2".into()]]).unwrap();
        sa.commit().unwrap();
        sb.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "x\n2\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn blank_lines_are_counted() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        std::fs::write(&p, "x,y\n1,2\n\n\n3,4\n5,6\n").unwrap();
        let t = read_table(p.to_str().unwrap()).unwrap();
        assert_eq!(t.lines, vec![2, 5, 6]);
    }

    /// Line numbers stay exact deep in a large file (they are counted on
    /// from the previous record, not from the start of the file for each).
    #[test]
    fn line_numbers_deep_in_a_large_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big.csv");
        let n = 30_000;
        let mut text = String::from("id,x,y,z,nx,ny,nz\n");
        for k in 0..n {
            if k % 1000 == 999 {
                text.push('\n');
            }
            text.push_str(&format!("p{k},{k},0.5,0.25,0,0,1\n"));
        }
        std::fs::write(&p, &text).unwrap();
        let t = read_table(p.to_str().unwrap()).unwrap();
        assert_eq!(t.rows.len(), n);
        // Row k sits on line 2 + k + (blank lines before it).
        for k in [0, 998, 999, 12_345, n - 1] {
            assert_eq!(t.lines[k], 2 + k as u64 + (k as u64 + 1) / 1000, "row {k}");
        }
        // A bad cell near the end is reported on its own line.
        let bad = text.replacen("p29990,29990,", "p29990,29x90,", 1);
        std::fs::write(&p, &bad).unwrap();
        let e = super::read_points(p.to_str().unwrap())
            .unwrap_err()
            .to_string();
        let line = 2 + 29_990 + 29_991 / 1000;
        assert!(e.contains(&format!("big.csv:{line}: field `x`")), "{e}");
    }
}
