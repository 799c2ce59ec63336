//! EULUMDAT (`.ldt`) photometric files (Stockmar 1990), one value per line.
//!
//! | line | field |
//! |---|---|
//! | 1 | company / format identification |
//! | 2 | `Ityp`: type indicator (0-3) |
//! | 3 | `Isym`: symmetry (0 none, 1 about the vertical axis, 2 about C0-C180, 3 about C90-C270, 4 about both) |
//! | 4, 5 | `Mc` C-planes in 0-360, their spacing `Dc` \[deg\] |
//! | 6, 7 | `Ng` intensities per C-plane, their spacing `Dg` \[deg\] |
//! | 8-12 | report number, luminaire name and number, file name, date/user |
//! | 13-15 | luminaire length (diameter), width (0: round), height \[mm\] |
//! | 16-21 | luminous area length (diameter), width (0: round), heights at C0, C90, C180, C270 \[mm\] |
//! | 22-25 | downward flux fraction [%], light output ratio [%], conversion factor `CFLI`, tilt \[deg\] |
//! | 26 | `n` lamp sets, then per set (6 blocks of `n` lines): number of lamps (negative: absolute photometry), lamp type, total lamp flux \[lm\], colour, colour rendering, wattage \[W\] |
//! | +10 | direct ratios for room indices 0.6-5 |
//! | +`Mc` | C angles \[deg\] |
//! | +`Ng` | gamma angles \[deg\] |
//! | rest | intensities [cd/klm], `Ng` per stored C-plane |
//!
//! The C-planes stored depend on `Isym` (1-based indices into the `Mc`
//! angles, wrapping past `Mc`): 0: 1..Mc; 1: 1 (C0); 2: 1..Mc/2+1 (C0-C180);
//! 3: 3Mc/4+1..3Mc/4+1+Mc/2 (C270-C90 through C0); 4: 1..Mc/4+1 (C0-C90).
//! The C angles must fit (else an error names the angle's line): listed
//! from 0 to below 360 degrees (but for Isym 1, whose one plane stands for
//! all), the stored planes running C0-C180 (2), C270-C0-C90 (3) or C0-C90
//! (4); the gamma angles ascend within 0-180.
//! A table stored as C270-C90 is turned into the equivalent C90-C270 half
//! (the mirror image `C -> 180 - C`) so that every [`Photometry`] keeps its
//! horizontal angles ascending.
//!
//! Intensities become candela as `value x flux / 1000 x CFLI`, with the total
//! lamp flux of the first lamp set (the standard set to which the table
//! refers; the others are alternatives and are listed only). Decimal commas
//! are accepted.

use super::{
    Opening, OpeningShape, PhotometricType, Photometry, PhotometryError, check_angles, text_lines,
    whole,
};

/// Most C-planes and gamma angles per plane.
const MAX_ANGLES: usize = 100_000;
/// Most lamp sets.
const MAX_SETS: usize = 1_000;

struct Lines<'a> {
    lines: Vec<&'a str>,
    next: usize,
    file: &'a str,
}

impl Lines<'_> {
    fn err(&self, line: usize, field: &str, message: impl Into<String>) -> PhotometryError {
        PhotometryError {
            file: self.file.to_string(),
            line,
            field: field.to_string(),
            message: message.into(),
        }
    }

    /// The next line as text, with its 1-based number.
    fn text(&mut self, field: &str) -> Result<(String, usize), PhotometryError> {
        let Some(l) = self.lines.get(self.next) else {
            return Err(self.err(self.lines.len(), field, "the file ends before this line"));
        };
        self.next += 1;
        Ok((l.trim().to_string(), self.next))
    }

    /// The next line as a finite number (a decimal comma is accepted).
    fn number(&mut self, field: &str) -> Result<f64, PhotometryError> {
        let (s, line) = self.text(field)?;
        match s.replace(',', ".").parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(line, field, format!("`{s}` is not a finite number"))),
        }
    }

    /// The next line as a whole number in `lo..=hi`.
    fn count(&mut self, field: &str, lo: i64, hi: i64) -> Result<i64, PhotometryError> {
        let v = self.number(field)?;
        whole(v, lo, hi).map_err(|m| self.err(self.next, field, m))
    }

    /// `n` numbers, one per line, checked to be available before allocating.
    fn numbers(&mut self, n: usize, field: &str) -> Result<Vec<f64>, PhotometryError> {
        let left = self.lines.len() - self.next;
        if n > left {
            return Err(self.err(
                self.lines.len(),
                field,
                format!("{n} lines expected, only {left} left in the file"),
            ));
        }
        (0..n)
            .map(|k| self.number(&format!("{field} #{}", k + 1)))
            .collect()
    }
}

/// Parse the text of an EULUMDAT file; `file` names it in messages.
pub fn parse(text: &str, file: &str) -> Result<Photometry, PhotometryError> {
    // A byte-order mark would only prefix the company identification
    // (text, unused): stripped all the same. Blank lines are not skipped:
    // an empty first line is an empty company identification.
    let mut l = Lines {
        lines: text_lines(text),
        next: 0,
        file,
    };
    l.text("company identification")?;
    l.count("Ityp (type indicator)", 0, 3)?;
    let isym = l.count("Isym (symmetry indicator)", 0, 4)?;
    let mc = l.count("Mc (number of C-planes)", 1, MAX_ANGLES as i64)? as usize;
    l.number("Dc (distance between C-planes)")?;
    let ng = l.count("Ng (intensities per C-plane)", 1, MAX_ANGLES as i64)? as usize;
    l.number("Dg (distance between intensities)")?;
    for field in [
        "measurement report number",
        "luminaire name",
        "luminaire number",
        "file name",
        "date/user",
    ] {
        l.text(field)?;
    }
    let mut dims = [0.0; 9];
    for (d, field) in dims.iter_mut().zip([
        "length/diameter of luminaire",
        "width of luminaire",
        "height of luminaire",
        "length/diameter of luminous area",
        "width of luminous area",
        "height of luminous area C0",
        "height of luminous area C90",
        "height of luminous area C180",
        "height of luminous area C270",
    ]) {
        *d = l.number(field)?;
        if *d < 0.0 {
            return Err(l.err(
                l.next,
                field,
                format!("must be >= 0 [mm], got {}", crate::io::format_number(*d)),
            ));
        }
    }
    l.number("downward flux fraction")?;
    l.number("light output ratio")?;
    let cfli = l.number("conversion factor for luminous intensities")?;
    if cfli <= 0.0 {
        return Err(l.err(
            l.next,
            "conversion factor for luminous intensities",
            format!("must be > 0, got {}", crate::io::format_number(cfli)),
        ));
    }
    l.number("tilt of luminaire during measurement")?;
    let sets = l.count("number of standard sets of lamps", 1, MAX_SETS as i64)? as usize;
    let lamps: Vec<f64> = l.numbers(sets, "number of lamps")?;
    if let Some(k) = lamps.iter().position(|n| n.fract() != 0.0 || *n == 0.0) {
        return Err(l.err(
            l.next - sets + k + 1,
            "number of lamps",
            format!(
                "must be a non-zero whole number (negative: absolute photometry), got {}",
                lamps[k]
            ),
        ));
    }
    for k in 0..sets {
        l.text(&format!("type of lamps #{}", k + 1))?;
    }
    let flux = l.numbers(sets, "total luminous flux of lamps")?;
    if let Some(k) = flux.iter().position(|f| *f <= 0.0) {
        return Err(l.err(
            l.next - sets + k + 1,
            "total luminous flux of lamps",
            format!(
                "must be > 0 [lm], got {}",
                crate::io::format_number(flux[k])
            ),
        ));
    }
    for field in ["colour appearance", "colour rendering group"] {
        for k in 0..sets {
            l.text(&format!("{field} #{}", k + 1))?;
        }
    }
    let watts = l.numbers(sets, "wattage including ballast")?;
    l.numbers(10, "direct ratio")?;
    let c_line = l.next + 1;
    let c_all = l.numbers(mc, "C angle")?;
    check_angles(&c_all, 0.0, 360.0, |m| l.err(c_line, "C angles", m))?;
    let g_line = l.next + 1;
    let gamma = l.numbers(ng, "gamma angle")?;
    check_angles(&gamma, 0.0, 180.0, |m| l.err(g_line, "gamma angles", m))?;
    let (mc1, mc2) = match isym {
        0 => (1, mc),
        1 => (1, 1),
        2 => (1, mc / 2 + 1),
        3 => (3 * mc / 4 + 1, 3 * mc / 4 + 1 + mc / 2),
        _ => (1, mc / 4 + 1),
    };
    if isym >= 2 && !mc.is_multiple_of(4) && !(isym == 2 && mc.is_multiple_of(2)) {
        return Err(l.err(
            4,
            "Mc (number of C-planes)",
            format!(
                "Isym {isym} needs Mc divisible by {}, got {mc}",
                if isym == 2 { 2 } else { 4 }
            ),
        ));
    }
    check_symmetry_angles(isym, &c_all, |k, m| l.err(c_line + k, "C angles", m))?;
    let scale = flux[0] / 1000.0 * cfli;
    let mut planes: Vec<(f64, Vec<f64>)> = Vec::with_capacity(mc2 - mc1 + 1);
    for k in mc1..=mc2 {
        let c = c_all[(k - 1) % mc];
        let line = l.next + 1;
        let row = l.numbers(ng, &format!("intensity in C-plane {c}"))?;
        if let Some(i) = row.iter().position(|v| *v < 0.0) {
            return Err(l.err(
                line + i,
                "intensities",
                format!(
                    "must be >= 0 [cd/klm], got {}",
                    crate::io::format_number(row[i])
                ),
            ));
        }
        let c = if isym == 3 { (540.0 - c) % 360.0 } else { c };
        planes.push((c, row.into_iter().map(|v| v * scale).collect()));
    }
    if let Some(extra) = l.lines[l.next..].iter().position(|s| !s.trim().is_empty()) {
        let line = l.next + extra + 1;
        return Err(l.err(
            line,
            "end of file",
            "unexpected data after the last intensity",
        ));
    }
    planes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let h_angles: Vec<f64> = planes.iter().map(|p| p.0).collect();
    let absolute = lamps[0] < 0.0;
    let [_, _, _, la, wa, h0, h90, h180, h270] = dims;
    let round = wa == 0.0 && la > 0.0;
    let shape = if round {
        OpeningShape::Ellipse
    } else if la != 0.0 || wa != 0.0 {
        OpeningShape::Rectangle
    } else {
        OpeningShape::Point
    };
    Ok(Photometry {
        kind: PhotometricType::C,
        v_angles: gamma,
        h_angles,
        candela: planes.into_iter().map(|p| p.1).collect(),
        lamp_lumens: (!absolute).then_some(flux[0]),
        opening: Opening {
            width: if wa == 0.0 { la } else { wa } / 1000.0,
            length: if wa == 0.0 { 0.0 } else { la / 1000.0 },
            height: (h0 + h90 + h180 + h270) / 4000.0,
            round,
            shape,
        },
        watts: (watts[0] > 0.0).then_some(watts[0]),
        format: "EULUMDAT".to_string(),
        tilt: None,
    })
}

/// Check the `Mc` C angles `c` (already ascending within [0, 360]) against
/// the symmetry `isym`: every table but a rotational one (1, whose one
/// plane stands for all) lists the C-planes from 0 to below 360 degrees,
/// and the planes stored must be the half or quarter the symmetry names:
/// 2: planes 1..Mc/2+1 from C0 to C180; 3: planes 3Mc/4+1..Mc, 1..Mc/4+1
/// from C270 through C0 to C90; 4: planes 1..Mc/4+1 from C0 to C90. `err`
/// gets the 0-based index of the angle at fault and the message.
fn check_symmetry_angles(
    isym: i64,
    c: &[f64],
    err: impl Fn(usize, String) -> PhotometryError,
) -> Result<(), PhotometryError> {
    let mc = c.len();
    let name = match isym {
        0 => "Isym 0 (no symmetry)",
        2 => "Isym 2 (symmetric about C0-C180)",
        3 => "Isym 3 (symmetric about C90-C270)",
        4 => "Isym 4 (symmetric about C0-C180 and C90-C270)",
        _ => return Ok(()),
    };
    let f = crate::io::format_number;
    if c[0] != 0.0 {
        return Err(err(
            0,
            format!(
                "{name} needs the C angles to start at 0 degrees, got {}",
                f(c[0])
            ),
        ));
    }
    if c[mc - 1] >= 360.0 {
        return Err(err(
            mc - 1,
            format!(
                "{name} needs the C angles below 360 degrees (360 is C0 again), got {} (angle {mc})",
                f(c[mc - 1])
            ),
        ));
    }
    // (0-based index, the angle it must have, the stored range in words).
    let ends: &[(usize, f64, &str)] = match isym {
        2 => &[(mc / 2, 180.0, "planes 1 to Mc/2+1 must run from C0 to C180")],
        3 => &[
            (
                3 * mc / 4,
                270.0,
                "planes 3Mc/4+1 to Mc and 1 to Mc/4+1 must run from C270 through C0 to C90",
            ),
            (
                mc / 4,
                90.0,
                "planes 3Mc/4+1 to Mc and 1 to Mc/4+1 must run from C270 through C0 to C90",
            ),
        ],
        4 => &[(mc / 4, 90.0, "planes 1 to Mc/4+1 must run from C0 to C90")],
        _ => &[],
    };
    for &(k, want, range) in ends {
        if c[k] != want {
            return Err(err(
                k,
                format!(
                    "{name} stores {range} (Mc = {mc}): C angle {} must be {}, got {}",
                    k + 1,
                    f(want),
                    f(c[k])
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::Symmetry;
    use super::*;

    /// An EULUMDAT file with `isym`, `mc` C-planes, gamma 0/45/90, two lamp
    /// sets (the first: `lamps` lamps, 2000 lm), and the stored planes' values
    /// `rows` [cd/klm] (one `Vec` per stored plane). `comma` writes decimal commas.
    pub(crate) fn ldt(isym: u8, mc: usize, lamps: i32, rows: &[Vec<f64>], comma: bool) -> String {
        let dc = 360.0 / mc as f64;
        let mut s = vec![
            "lumest test".to_string(),
            "1".into(),
            isym.to_string(),
            mc.to_string(),
            dc.to_string(),
            "3".into(),
            "45".into(),
            "r1".into(),
            "test luminaire".into(),
            "n1".into(),
            "t.ldt".into(),
            "2026".into(),
            "600".into(),
            "0".into(),
            "50".into(),
            "500".into(),
            "0".into(),
            "10".into(),
            "10".into(),
            "10".into(),
            "10".into(),
            "100".into(),
            "80.5".into(),
            "1".into(),
            "0".into(),
            "2".into(),
            lamps.to_string(),
            "1".into(),
            "LED".into(),
            "LED".into(),
            "2000".into(),
            "3000".into(),
            "840".into(),
            "830".into(),
            "1A".into(),
            "1A".into(),
            "20".into(),
            "30".into(),
        ];
        s.extend((0..10).map(|k| format!("0.{k}")));
        s.extend((0..mc).map(|k| (k as f64 * dc).to_string()));
        s.extend(["0", "45", "90"].map(String::from));
        for r in rows {
            s.extend(r.iter().map(|v| v.to_string()));
        }
        let mut t = s.join("\r\n") + "\r\n";
        if comma {
            t = t.replace('.', ",");
        }
        t
    }

    /// Lone-CR line ends (old Mac OS) and a DOS end-of-file mark (Ctrl-Z)
    /// after the last intensity read as the CR LF file does (before: no
    /// lines, and "unexpected data after the last intensity").
    #[test]
    fn old_line_ends_and_end_of_file_marks() {
        let rows: Vec<Vec<f64>> = (0..5).map(|k| vec![100.0 + k as f64, 50.0, 0.0]).collect();
        let crlf = ldt(2, 8, 1, &rows, false);
        let want = parse(&crlf, "t.ldt").unwrap();
        for text in [
            crlf.replace("\r\n", "\r"),
            crlf.replace("\r\n", "\n"),
            format!("{crlf}\u{1a}"),
            format!("{crlf}\r\n\u{1a}"),
        ] {
            assert_eq!(parse(&text, "t.ldt").unwrap(), want, "{text:?}");
        }
    }

    #[test]
    fn every_symmetry_stores_its_planes() {
        // Mc = 8 (Dc = 45): plane counts 8, 1, 5, 5, 3.
        for (isym, n, sym) in [
            (0u8, 8, Symmetry::None),
            (1, 1, Symmetry::Rotational),
            (2, 5, Symmetry::BilateralC0),
            (3, 5, Symmetry::BilateralC90),
            (4, 3, Symmetry::Quadrant),
        ] {
            let rows: Vec<Vec<f64>> = (0..n).map(|k| vec![100.0 + k as f64, 50.0, 0.0]).collect();
            let p = parse(&ldt(isym, 8, 1, &rows, false), "t.ldt").unwrap();
            assert_eq!(p.candela.len(), n, "isym {isym}");
            assert_eq!(p.symmetry(), sym, "isym {isym}: {:?}", p.h_angles);
            // cd/klm times 2000 lm / 1000.
            assert_eq!(p.candela[0][1], 100.0);
            assert_eq!(p.lamp_lumens, Some(2000.0));
            assert_eq!(p.watts, Some(20.0));
            if isym == 3 {
                // Stored C270, C315, C0, C45, C90 -> mirrored C270, C225, C180, C135, C90.
                assert_eq!(p.h_angles, [90.0, 135.0, 180.0, 225.0, 270.0]);
                assert_eq!(p.candela[0][0], 2.0 * 104.0);
                assert_eq!(p.candela[4][0], 2.0 * 100.0);
            }
        }
    }

    #[test]
    fn absolute_photometry_decimal_commas_and_round_openings() {
        let rows = vec![vec![1.5, 2.5, 0.0]];
        let p = parse(&ldt(1, 8, -1, &rows, true), "t.ldt").unwrap();
        assert_eq!(p.lamp_lumens, None);
        assert_eq!(p.candela[0], [3.0, 5.0, 0.0]);
        assert!(p.opening.round);
        assert!((p.opening.width - 0.5).abs() < 1e-15 && p.opening.height == 0.01);
    }

    /// A byte-order mark before the company identification changes
    /// nothing (as UTF-8 bytes read from disk, or as U+FEFF); an empty
    /// company line is still a line.
    #[test]
    fn a_byte_order_mark_is_harmless() {
        let good = ldt(1, 8, 1, &[vec![1.0, 2.0, 3.0]], false);
        let want = parse(&good, "t.ldt").unwrap();
        assert_eq!(want.candela, [vec![2.0, 4.0, 6.0]]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bom.ldt");
        std::fs::write(&path, format!("\u{feff}{good}").as_bytes()).unwrap();
        assert_eq!(super::super::read(&path).unwrap(), want);
        assert_eq!(parse(&format!("\u{feff}{good}"), "t.ldt").unwrap(), want);
        let blank = good.replacen("lumest test", "", 1);
        assert_eq!(parse(&blank, "t.ldt").unwrap(), want);
    }

    #[test]
    fn errors_name_line_and_field() {
        let good = ldt(1, 8, 1, &[vec![1.0, 2.0, 3.0]], false);
        let lines: Vec<&str> = good.lines().collect();
        let with = |k: usize, v: &str| {
            let mut l = lines.clone();
            l[k - 1] = v;
            l.join("\n")
        };
        for (text, line, field) in [
            (with(3, "7"), 3, "Isym (symmetry indicator)"),
            (with(4, "x"), 4, "Mc (number of C-planes)"),
            (with(31, "-5"), 31, "total luminous flux of lamps"),
            (with(61, "-1"), 61, "intensities"),
            (lines[..50].join("\n"), 50, "C angle"),
            (format!("{good}\n12\n"), 64, "end of file"),
        ] {
            let e = parse(&text, "t.ldt").unwrap_err();
            assert_eq!((e.line, e.field.as_str()), (line, field), "{e}");
        }
    }

    /// C angles that do not match the symmetry indicator are refused,
    /// naming the line of the angle at fault (the C angles of the helper's
    /// files start on line 49, the gamma angles follow them). Before, the
    /// reviewer's c5.ldt (Isym 0, C = 5, 35, ..., 335) was read as if its
    /// planes were where a 0-based table has them, and the other files
    /// here read silently with planes out of place.
    #[test]
    fn c_angles_must_fit_the_symmetry() {
        let with_c = |isym: u8, mc: usize, c: &[f64]| {
            let rows = vec![vec![1.0, 2.0, 3.0]; mc];
            let n = match isym {
                0 => mc,
                1 => 1,
                2 | 3 => mc / 2 + 1,
                _ => mc / 4 + 1,
            };
            let good = ldt(isym, mc, 1, &rows[..n], false);
            let mut lines: Vec<String> = good.lines().map(String::from).collect();
            for (k, a) in c.iter().enumerate() {
                lines[48 + k] = a.to_string();
            }
            lines.join("\n")
        };
        let step = |mc: usize, first: f64, dc: f64| -> Vec<f64> {
            (0..mc).map(|k| first + dc * k as f64).collect()
        };
        let mut c3 = step(8, 0.0, 45.0);
        c3[0] = 2.0;
        let mut c0 = step(8, 0.0, 45.0);
        c0[7] = 360.0;
        for (isym, mc, c, line, what) in [
            // The reviewer's c5.ldt: Isym 0, Mc 12, C = 5..335.
            (0u8, 12, step(12, 5.0, 30.0), 49, "start at 0"),
            (0, 8, c0, 56, "below 360"),
            // Planes 1..5 of Dc 40: C0..C160, not C0..C180.
            (
                2,
                8,
                step(8, 0.0, 40.0),
                53,
                "C angle 5 must be 180, got 160",
            ),
            // C0..C60, not C0..C90.
            (4, 8, step(8, 0.0, 30.0), 51, "C angle 3 must be 90, got 60"),
            // C270, C315, C2, C45, C90: before, the C2 plane was taken for C0.
            (3, 8, c3, 49, "start at 0"),
            (
                3,
                8,
                step(8, 0.0, 40.0),
                55,
                "C angle 7 must be 270, got 240",
            ),
        ] {
            let e = parse(&with_c(isym, mc, &c), "t.ldt").unwrap_err();
            assert_eq!((e.line, e.field.as_str()), (line, "C angles"), "{e}");
            assert!(e.to_string().contains(what), "{e}");
            assert!(
                e.to_string()
                    .starts_with(&format!("t.ldt:{line}: C angles: Isym {isym}")),
                "{e}"
            );
        }
        // Uneven but fitting angles are accepted: Isym 3 with C270, C300, C0,
        // C45, C90 stored; Isym 1 reads its one plane whatever the angles.
        let mut ok3 = step(8, 0.0, 45.0);
        ok3[7] = 300.0;
        let p = parse(&with_c(3, 8, &ok3), "t.ldt").unwrap();
        assert_eq!(p.h_angles, [90.0, 135.0, 180.0, 240.0, 270.0]);
        assert!(parse(&with_c(1, 8, &step(8, 5.0, 30.0)), "t.ldt").is_ok());
        // Gamma angles must ascend within [0, 180] (0, 95, 90 on lines
        // 57-59): the error names the first gamma line.
        let good = ldt(1, 8, 1, &[vec![1.0, 2.0, 3.0]], false);
        let mut lines: Vec<&str> = good.lines().collect();
        lines[57] = "95";
        let e = parse(&lines.join("\n"), "t.ldt").unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (57, "gamma angles"), "{e}");
    }

    #[test]
    fn no_panic_on_any_prefix_or_line_corruption() {
        let good = ldt(3, 8, 1, &vec![vec![1.0, 2.0, 3.0]; 5], false);
        for n in 0..good.len() {
            let _ = parse(&good[..n], "t.ldt");
        }
        let lines: Vec<&str> = good.lines().collect();
        for k in 0..lines.len() {
            for bad in ["", "-1", "1e999", "99999999", "0", "x"] {
                let mut l = lines.clone();
                l[k] = bad;
                let _ = parse(&l.join("\n"), "t.ldt");
            }
        }
    }
}
