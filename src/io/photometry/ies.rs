//! IES LM-63 photometric files: the 1986 layout (no header line), 1991
//! (`IESNA91`), 1995 (`IESNA:LM-63-1995`), 2002 (`IESNA:LM-63-2002`) and
//! 2019 (`IES:LM-63-2019`).
//!
//! Layout: an optional header line; keyword or label lines up to the
//! `TILT=` line; then a stream of numbers that may wrap anywhere (spaces,
//! tabs, commas and line ends all separate them):
//!
//! 1. with `TILT=INCLUDE` only: lamp-to-luminaire geometry, the number of
//!    tilt angles `n`, `n` angles, `n` multiplying factors;
//! 2. number of lamps, lumens per lamp (`-1`: absolute photometry),
//!    candela multiplier, number of vertical angles, number of horizontal
//!    angles, photometric type (1 = C, 2 = B, 3 = A), units (1 = feet,
//!    2 = metres), width, length, height of the luminous opening;
//! 3. ballast factor, a factor whose meaning depends on the version (the
//!    ballast-lamp photometric factor in 1986 and 1991, "future use" in
//!    1995 and 2002, the file-generation type in 2019), input watts;
//! 4. the vertical angles, the horizontal angles, and the candela values,
//!    all vertical angles of the first horizontal angle first.
//!
//! The intensity is the file's candela value times the candela multiplier
//! times the ballast factor, times the ballast-lamp photometric factor for
//! the versions that define one, 1986 and 1991 (as Radiance's `ies2rad`
//! and Ashdown's reference parser read them: never the 1995 and 2002
//! "future use" field, whatever it holds, nor the 2019 file-generation
//! type).
//! With `TILT=INCLUDE` the tilt table is kept ([`super::Tilt`]) and its
//! factor at the luminaire's installed tilt multiplies later, where the
//! light is placed (it depends on the aim); `lumest photometry` shows the
//! upright luminaire (tilt 0). A `TILT=<file>` reference is refused: the
//! data must be included. The signs of width, length and height give the opening's shape
//! (LM-63-2002's luminous shapes: [`opening`]).

use super::{
    Opening, PhotometricType, Photometry, PhotometryError, Tilt, TiltGeometry, check_angles,
    text_lines, whole,
};

/// Most angles per axis and values in a table (larger files are refused
/// before anything is allocated for them).
const MAX_ANGLES: usize = 100_000;
const MAX_VALUES: usize = 10_000_000;

/// The versions, by header line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Version {
    Lm1986,
    Lm1991,
    Lm1995,
    Lm2002,
    Lm2019,
}

/// Numbers after the `TILT=` line, each with its 1-based line.
struct Tokens<'a> {
    items: Vec<(&'a str, usize)>,
    next: usize,
    file: &'a str,
    last_line: usize,
}

impl<'a> Tokens<'a> {
    fn err(&self, line: usize, field: &str, message: impl Into<String>) -> PhotometryError {
        PhotometryError {
            file: self.file.to_string(),
            line,
            field: field.to_string(),
            message: message.into(),
        }
    }

    /// The next number, named `field` in messages.
    fn number(&mut self, field: &str) -> Result<(f64, usize), PhotometryError> {
        let Some(&(tok, line)) = self.items.get(self.next) else {
            return Err(self.err(self.last_line, field, "the file ends before this value"));
        };
        self.next += 1;
        match tok.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok((v, line)),
            _ => Err(self.err(line, field, format!("`{tok}` is not a finite number"))),
        }
    }

    /// The next number, which must be a whole number in `lo..=hi`.
    fn count(&mut self, field: &str, lo: i64, hi: i64) -> Result<i64, PhotometryError> {
        let (v, line) = self.number(field)?;
        whole(v, lo, hi).map_err(|m| self.err(line, field, m))
    }

    /// `n` numbers, checked to be available before allocating.
    fn numbers(&mut self, n: usize, field: &str) -> Result<Vec<f64>, PhotometryError> {
        let left = self.items.len() - self.next;
        if n > left {
            return Err(self.err(
                self.last_line,
                field,
                format!("{n} values expected, only {left} numbers left in the file"),
            ));
        }
        (0..n)
            .map(|k| self.number(&format!("{field} #{}", k + 1)).map(|v| v.0))
            .collect()
    }

    /// The 1-based line of the next number (or the last line).
    fn line(&self) -> usize {
        self.items.get(self.next).map_or(self.last_line, |t| t.1)
    }
}

/// Parse the text of an IES LM-63 file; `file` names it in messages.
pub fn parse(text: &str, file: &str) -> Result<Photometry, PhotometryError> {
    let err = |line: usize, field: &str, message: String| PhotometryError {
        file: file.to_string(),
        line,
        field: field.to_string(),
        message,
    };
    // A byte-order mark and blank lines before the first line are skipped
    // when looking for the version (left there, they would make a 2019
    // file read as 1986, its file-generation type a candela factor); line
    // numbers still count the blank lines.
    let lines: Vec<&str> = text_lines(text);
    let first = lines
        .iter()
        .map(|l| l.trim())
        .find(|l| !l.is_empty())
        .unwrap_or("");
    let version = match first {
        s if s.starts_with("IESNA:LM-63-1995") => Version::Lm1995,
        s if s.starts_with("IESNA:LM-63-2002") => Version::Lm2002,
        s if s.starts_with("IES:LM-63-2019") => Version::Lm2019,
        s if s.starts_with("IESNA91") => Version::Lm1991,
        s if s.starts_with("IESNA") || s.starts_with("IES:") => {
            return Err(err(
                1,
                "header",
                format!(
                    "unknown LM-63 version `{s}` (known: 1986 without a header, IESNA91, IESNA:LM-63-1995, IESNA:LM-63-2002, IES:LM-63-2019)"
                ),
            ));
        }
        _ => Version::Lm1986,
    };
    let Some(tilt_at) = lines.iter().position(|l| {
        // (`TILT`, then `=`: a 1986 label line may begin with a word
        // such as `TILTED`.)
        l.trim_start()
            .strip_prefix("TILT")
            .is_some_and(|r| r.trim_start().starts_with('='))
    }) else {
        return Err(err(0, "TILT", "no `TILT=` line".into()));
    };
    let tilt_line = lines[tilt_at].trim();
    let tilt = tilt_line
        .strip_prefix("TILT")
        .map(str::trim_start)
        .and_then(|s| s.strip_prefix('='))
        .map(str::trim)
        .ok_or_else(|| {
            err(
                tilt_at + 1,
                "TILT",
                format!("expected `TILT=`, got `{tilt_line}`"),
            )
        })?;
    let include = match tilt {
        "NONE" => false,
        "INCLUDE" => true,
        other => {
            return Err(err(
                tilt_at + 1,
                "TILT",
                format!(
                    "`TILT={other}` refers to a separate tilt file, which lumest does not read: \
                     put the data in this file with TILT=INCLUDE, or use TILT=NONE"
                ),
            ));
        }
    };
    let mut t = Tokens {
        items: lines
            .iter()
            .enumerate()
            .skip(tilt_at + 1)
            .flat_map(|(i, l)| {
                l.split(|c: char| c.is_whitespace() || c == ',')
                    .filter(|s| !s.is_empty())
                    .map(move |s| (s, i + 1))
            })
            .collect(),
        next: 0,
        file,
        last_line: lines.len(),
    };
    let tilt = if include {
        let geometry = match t.count("TILT lamp-to-luminaire geometry", 1, 3)? {
            1 => TiltGeometry::Vertical,
            2 => TiltGeometry::HorizontalC0,
            _ => TiltGeometry::HorizontalC90,
        };
        let n = t.count("number of TILT angles", 1, MAX_ANGLES as i64)? as usize;
        let line = t.line();
        let angles = t.numbers(n, "TILT angle")?;
        check_angles(&angles, -180.0, 180.0, |m| err(line, "TILT angles", m))?;
        let line = t.line();
        let factors = t.numbers(n, "TILT multiplying factor")?;
        if let Some(f) = factors.iter().find(|f| **f < 0.0) {
            return Err(err(
                line,
                "TILT multiplying factors",
                format!("must be >= 0, got {}", crate::io::format_number(*f)),
            ));
        }
        Some(Tilt {
            geometry,
            angles,
            factors,
        })
    } else {
        None
    };
    let line = t.line();
    let lamps = t.count("number of lamps", 1, 1_000_000)?;
    let (lumens, l_line) = t.number("lumens per lamp")?;
    if !(lumens > 0.0 || lumens == -1.0) {
        return Err(err(
            l_line,
            "lumens per lamp",
            format!(
                "must be > 0, or -1 for absolute photometry, got {}",
                crate::io::format_number(lumens)
            ),
        ));
    }
    let (multiplier, m_line) = t.number("candela multiplier")?;
    if multiplier <= 0.0 {
        return Err(err(
            m_line,
            "candela multiplier",
            format!("must be > 0, got {}", crate::io::format_number(multiplier)),
        ));
    }
    let n_v = t.count("number of vertical angles", 1, MAX_ANGLES as i64)? as usize;
    let n_h = t.count("number of horizontal angles", 1, MAX_ANGLES as i64)? as usize;
    if n_v * n_h > MAX_VALUES {
        return Err(err(
            line,
            "number of angles",
            format!("{n_v} x {n_h} candela values: at most {MAX_VALUES} are supported"),
        ));
    }
    let kind = match t.count("photometric type", 1, 3)? {
        1 => PhotometricType::C,
        2 => PhotometricType::B,
        _ => PhotometricType::A,
    };
    let unit = if t.count("units type", 1, 2)? == 1 {
        0.3048
    } else {
        1.0
    };
    let (w, _) = t.number("width")?;
    let (l, _) = t.number("length")?;
    let (h, _) = t.number("height")?;
    let (ballast, b_line) = t.number("ballast factor")?;
    if ballast <= 0.0 {
        return Err(err(
            b_line,
            "ballast factor",
            format!("must be > 0, got {}", crate::io::format_number(ballast)),
        ));
    }
    let (second, s_line) = t.number(match version {
        Version::Lm1995 | Version::Lm2002 => "future use",
        Version::Lm2019 => "file generation type",
        _ => "ballast-lamp photometric factor",
    })?;
    let lamp_factor = match version {
        Version::Lm1986 | Version::Lm1991 => {
            if second <= 0.0 {
                return Err(err(
                    s_line,
                    "ballast-lamp photometric factor",
                    format!("must be > 0, got {}", crate::io::format_number(second)),
                ));
            }
            second
        }
        Version::Lm1995 | Version::Lm2002 | Version::Lm2019 => 1.0,
    };
    let (watts, w_line) = t.number("input watts")?;
    if watts < 0.0 {
        return Err(err(
            w_line,
            "input watts",
            format!("must be >= 0, got {}", crate::io::format_number(watts)),
        ));
    }
    let line = t.line();
    let v_angles = t.numbers(n_v, "vertical angle")?;
    let (v_lo, v_hi) = match kind {
        PhotometricType::C => (0.0, 180.0),
        _ => (-90.0, 90.0),
    };
    check_angles(&v_angles, v_lo, v_hi, |m| err(line, "vertical angles", m))?;
    let line = t.line();
    let h_angles = t.numbers(n_h, "horizontal angle")?;
    let (h_lo, h_hi) = match kind {
        PhotometricType::C => (0.0, 360.0),
        _ => (-90.0, 90.0),
    };
    check_angles(&h_angles, h_lo, h_hi, |m| err(line, "horizontal angles", m))?;
    if kind == PhotometricType::C && n_h > 1 {
        let (first, last) = (h_angles[0], h_angles[n_h - 1]);
        // A table from 0 to a last angle past 180 (not 360) is a full
        // turn that wraps from its last plane to C360 = C0 (as Radiance's
        // ies2rad reads it).
        let known =
            (first == 0.0 && (last == 90.0 || last >= 180.0)) || (first == 90.0 && last == 270.0);
        if !known {
            return Err(err(
                line,
                "horizontal angles",
                format!(
                    "a type C table must span 0-90, 0-180, 0 to 180-360 (a full turn) or 90-270 degrees, got {first}-{last}"
                ),
            ));
        }
    }
    let scale = multiplier * ballast * lamp_factor;
    let mut candela = Vec::with_capacity(n_h);
    for (i, c) in h_angles.iter().enumerate() {
        let line = t.line();
        let row = t.numbers(n_v, &format!("candela value at horizontal angle {c}"))?;
        if let Some(k) = row.iter().position(|v| *v < 0.0) {
            return Err(err(
                line,
                "candela values",
                format!(
                    "value {} of horizontal angle #{} is {}: must be >= 0",
                    k + 1,
                    i + 1,
                    row[k]
                ),
            ));
        }
        candela.push(row.into_iter().map(|v| v * scale).collect());
    }
    if t.next < t.items.len() {
        let (tok, line) = t.items[t.next];
        return Err(err(
            line,
            "end of file",
            format!("unexpected `{tok}` after the last candela value"),
        ));
    }
    let opening = opening(version, w, l, h, unit);
    Ok(Photometry {
        kind,
        v_angles,
        h_angles,
        candela,
        lamp_lumens: (lumens > 0.0).then_some(lumens * lamps as f64),
        opening,
        watts: (watts > 0.0).then_some(watts),
        format: match version {
            Version::Lm1986 => "IES LM-63-1986",
            Version::Lm1991 => "IES LM-63-1991",
            Version::Lm1995 => "IES LM-63-1995",
            Version::Lm2002 => "IES LM-63-2002",
            Version::Lm2019 => "IES LM-63-2019",
        }
        .to_string(),
        tilt,
    })
}

/// The luminous opening \[m\] of a file of `version` from its width `w`,
/// length `l` and height `h` (signed, in the file's units; `unit` \[m\] per
/// unit).
///
/// LM-63-2002 and 2019 (Table 1 of LM-63-2002), by the signs of `(w, l, h)`:
/// `(0, 0, 0)` a point; `(+, +, 0)` a rectangle, `(+, +, +)` one with
/// luminous sides; `(-, -, 0)` a circle or an ellipse, `(-, -, +)` a
/// vertical circular or elliptical cylinder; `(-, -, -)` a sphere or an
/// ellipsoid; `(-, +, -)` a horizontal cylinder along the photometric
/// horizontal (C0-C180), `(+, -, -)` one across it (along C90-C270);
/// `(-, 0, -)` a vertical circle or ellipse facing the photometric
/// horizontal, `(0, -, -)` one facing across it.
///
/// LM-63-1995 (as Radiance's `ies2rad` reads it): `(-, 0, -)` a sphere of
/// diameter `|w|` (an ellipsoid `|w| x |w| x |h|` where they differ),
/// `(-, +, -)` and `(+, -, -)` ellipsoids, `(0, +, -)` and `(+, 0, -)`
/// horizontal cylinders along C0 and C90 (diameter `|h|`), `(-, +, h)`
/// and `(+, -, h)` with `h >= 0` ellipses (with luminous sides `h`).
/// LM-63-1986 and 1991: `(-, +, 0)` an ellipse, `(-, +, +)` an ellipsoid.
///
/// Any other negative width is read as before these shapes were known: a
/// disc of diameter `|w|` with luminous sides `|h|` (so `(-, 0, 0)`, the
/// 1986-1995 circle, and `(-, 0, +)`, their vertical cylinder); any other
/// combination a rectangle `|w| x |l|` with sides `|h|`.
fn opening(version: Version, w: f64, l: f64, h: f64, unit: f64) -> Opening {
    use super::OpeningShape as S;
    let (wa, la, ha) = (w.abs() * unit, l.abs() * unit, h.abs() * unit);
    let of = |shape: S, width: f64, length: f64, height: f64| Opening {
        width,
        length,
        height,
        round: shape == S::Ellipse,
        shape,
    };
    // An ellipse's length 0 stands for a circle (as EULUMDAT writes it).
    let ellipse = |width: f64, length: f64, sides: f64| {
        let length = if length == width { 0.0 } else { length };
        of(S::Ellipse, width, length, sides)
    };
    let sign = |v: f64| (v > 0.0) as i8 - (v < 0.0) as i8;
    let shape = match version {
        Version::Lm2002 | Version::Lm2019 => match (sign(w), sign(l), sign(h)) {
            (-1, -1, 0 | 1) => Some(ellipse(wa, la, ha)),
            (-1, -1, -1) => Some(of(S::Ellipsoid, wa, la, ha)),
            (-1, 1, -1) => Some(of(S::CylinderC0, wa, la, ha)),
            (1, -1, -1) => Some(of(S::CylinderC90, wa, la, ha)),
            (-1, 0, -1) => Some(of(S::VerticalEllipseC0, wa, 0.0, ha)),
            (0, -1, -1) => Some(of(S::VerticalEllipseC90, 0.0, la, ha)),
            _ => None,
        },
        Version::Lm1995 => match (sign(w), sign(l), sign(h)) {
            (-1, 0, -1) => Some(of(S::Ellipsoid, wa, wa, ha)),
            (-1, 1, -1) | (1, -1, -1) => Some(of(S::Ellipsoid, wa, la, ha)),
            (0, 1, -1) => Some(of(S::CylinderC0, ha, la, ha)),
            (1, 0, -1) => Some(of(S::CylinderC90, wa, ha, ha)),
            (-1, 1, 0 | 1) | (1, -1, 0 | 1) => Some(ellipse(wa, la, ha)),
            _ => None,
        },
        Version::Lm1986 | Version::Lm1991 => match (sign(w), sign(l), sign(h)) {
            (-1, 1, 0) => Some(ellipse(wa, la, 0.0)),
            (-1, 1, 1) => Some(of(S::Ellipsoid, wa, la, ha)),
            _ => None,
        },
    };
    shape.unwrap_or(if w < 0.0 {
        of(S::Ellipse, wa, 0.0, ha)
    } else if wa == 0.0 && la == 0.0 {
        // No opening; a height alone makes none.
        of(S::Point, 0.0, 0.0, ha)
    } else {
        of(S::Rectangle, wa, la, ha)
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The pendant luminaire printed in seed 001 (LM-63-1995).
    pub(crate) const PENDANT: &str = "IESNA:LM-63-1995
[TEST]     21307
[MANUFAC]ECLIPSE LIGHTING - PENDANT LUMINAIRE
[LUMCAT]ME-XL1-QL165-277VOLT
[LUMINAIRE]WHITE PLASTIC TUBE WITH TOP AND BOTTOM OPEN
[LAMP]ONE PHILIPS 165 WATT INDUCTION LAMP
[LAMPCAT]QL165W/840. LUMEN RATING = 8289 LMS.
[OTHER]ONE PHILIPS QL165W S/1 GENERATOR OPERATING AT 277 VAC AND 147 WATTS
TILT=NONE
1   8289   1   73  1   1  1   -1.00   0.00   1.92  1  1
147.0000

0 2.5 5 7.5 10 12.5 15 17.5 20 22.5 25 27.5 30 32.5 35 37.5
40 42.5 45 47.5 50 52.5 55 57.5 60 62.5 65 67.5 70 72.5 75
77.5 80 82.5 85 87.5 90 92.5 95 97.5 100 102.5 105 107.5 110
112.5 115 117.5 120 122.5 125 127.5 130 132.5 135 137.5 140
142.5 145 147.5 150 152.5 155 157.5 160 162.5 165 167.5 170
172.5 175 177.5 180
0

879.2      897.2      941.6     1001.1     1060.8     1116.3     1165.3     1171.1     1131.6     1064.3
986.6      910.8      845.1      792.7      760.3      745.7      735.6      724.5      714.6      703.8
693.0      683.0      675.6      672.1      672.0      673.9      675.9      677.6      679.3      680.9
682.3      682.9      682.7      681.2      678.5      676.6      680.7      684.8      683.3      680.9
676.9      671.2      664.1      655.9      646.6      636.3      625.0      612.7      599.6      586.1
572.3      558.1      544.0      530.5      517.8      506.6      496.4      486.5      477.0      469.6
470.0      482.8      502.2      520.6      526.0      496.0      414.4      315.6      235.7      169.7
108.4       59.4       35.8
";

    #[test]
    fn reads_the_pendant_of_seed_001() {
        let p = parse(PENDANT, "pendant.ies").unwrap();
        assert_eq!(p.format, "IES LM-63-1995");
        assert_eq!(p.kind, PhotometricType::C);
        assert_eq!(p.v_angles.len(), 73);
        assert_eq!(p.h_angles, [0.0]);
        assert_eq!(p.candela[0][0], 879.2);
        assert_eq!(p.candela[0][72], 35.8);
        assert_eq!(p.lamp_lumens, Some(8289.0));
        assert_eq!(p.watts, Some(147.0));
        assert_eq!(p.symmetry(), super::super::Symmetry::Rotational);
        // Units 1: feet; a negative width is a round opening.
        assert!(p.opening.round);
        assert!((p.opening.width - 0.3048).abs() < 1e-15);
        assert!((p.opening.height - 1.92 * 0.3048).abs() < 1e-15);
    }

    /// Every LM-63-2002 luminous shape (its Table 1), written in metres,
    /// parsed to its shape and dimensions; the same signs in an LM-63-1995
    /// file where that version reads them otherwise; and the older forms
    /// kept (a negative width alone: a disc).
    #[test]
    fn luminous_shapes_by_their_signs() {
        use super::super::OpeningShape as S;
        let file = |version: &str, w: f64, l: f64, h: f64| {
            let text = format!(
                "{version}\n[TEST] shape\nTILT=NONE\n1 1000 1 3 1 1 2 {w} {l} {h}\n1 1 0\n0 45 90\n0\n100 80 50\n"
            );
            parse(&text, "s.ies").unwrap().opening
        };
        let v02 = "IESNA:LM-63-2002";
        let cases = [
            ((0.0, 0.0, 0.0), S::Point, (0.0, 0.0, 0.0), "point"),
            (
                (0.3, 1.2, 0.0),
                S::Rectangle,
                (0.3, 1.2, 0.0),
                "rectangular",
            ),
            (
                (0.3, 1.2, 0.1),
                S::Rectangle,
                (0.3, 1.2, 0.1),
                "rectangular with luminous sides",
            ),
            ((-0.4, -0.4, 0.0), S::Ellipse, (0.4, 0.0, 0.0), "circular"),
            ((-0.4, -0.6, 0.0), S::Ellipse, (0.4, 0.6, 0.0), "ellipse"),
            (
                (-0.4, -0.4, 0.2),
                S::Ellipse,
                (0.4, 0.0, 0.2),
                "vertical cylinder",
            ),
            (
                (-0.4, -0.6, 0.2),
                S::Ellipse,
                (0.4, 0.6, 0.2),
                "vertical elliptical cylinder",
            ),
            ((-0.4, -0.4, -0.4), S::Ellipsoid, (0.4, 0.4, 0.4), "sphere"),
            (
                (-0.4, -0.6, -0.2),
                S::Ellipsoid,
                (0.4, 0.6, 0.2),
                "ellipsoidal spheroid",
            ),
            (
                (-0.1, 1.2, -0.1),
                S::CylinderC0,
                (0.1, 1.2, 0.1),
                "horizontal cylinder along photometric horizontal",
            ),
            (
                (-0.1, 1.2, -0.2),
                S::CylinderC0,
                (0.1, 1.2, 0.2),
                "horizontal elliptical cylinder along photometric horizontal",
            ),
            (
                (1.2, -0.1, -0.1),
                S::CylinderC90,
                (1.2, 0.1, 0.1),
                "horizontal cylinder perpendicular to photometric horizontal",
            ),
            (
                (1.2, -0.1, -0.2),
                S::CylinderC90,
                (1.2, 0.1, 0.2),
                "horizontal elliptical cylinder perpendicular to photometric horizontal",
            ),
            (
                (-0.3, 0.0, -0.3),
                S::VerticalEllipseC0,
                (0.3, 0.0, 0.3),
                "vertical circle facing photometric horizontal",
            ),
            (
                (-0.3, 0.0, -0.5),
                S::VerticalEllipseC0,
                (0.3, 0.0, 0.5),
                "vertical ellipse facing photometric horizontal",
            ),
            (
                (0.0, -0.3, -0.3),
                S::VerticalEllipseC90,
                (0.0, 0.3, 0.3),
                "vertical circle facing perpendicular to photometric horizontal",
            ),
            (
                (0.0, -0.3, -0.5),
                S::VerticalEllipseC90,
                (0.0, 0.3, 0.5),
                "vertical ellipse facing perpendicular to photometric horizontal",
            ),
            // Not in the 2002 table: read as before (a disc of diameter |w|).
            ((-0.3, 0.0, 0.0), S::Ellipse, (0.3, 0.0, 0.0), "circular"),
            (
                (-0.3, 0.0, 0.5),
                S::Ellipse,
                (0.3, 0.0, 0.5),
                "vertical cylinder",
            ),
        ];
        for ((w, l, h), shape, (ww, ll, hh), name) in cases {
            for version in [v02, "IES:LM-63-2019"] {
                let o = file(version, w, l, h);
                assert_eq!(o.shape, shape, "{version} ({w}, {l}, {h})");
                assert_eq!(
                    (o.width, o.length, o.height),
                    (ww, ll, hh),
                    "({w}, {l}, {h})"
                );
                assert_eq!(o.round, shape == S::Ellipse);
                assert_eq!(shape.name(o.width, o.length, o.height), name);
            }
        }
        // Feet: every dimension converted.
        let o = parse(
            "IESNA:LM-63-2002\nTILT=NONE\n1 1000 1 3 1 1 1 -1 -1 -1\n1 1 0\n0 45 90\n0\n100 80 50\n",
            "f.ies",
        )
        .unwrap()
        .opening;
        assert_eq!((o.width, o.length, o.height), (0.3048, 0.3048, 0.3048));
        // LM-63-1995: (-, 0, -) a sphere, (0, +, -) a cylinder along C0,
        // (-, +, -) an ellipsoid.
        let v95 = "IESNA:LM-63-1995";
        let o = file(v95, -0.4, 0.0, -0.4);
        assert_eq!(
            (o.shape, o.width, o.length, o.height),
            (S::Ellipsoid, 0.4, 0.4, 0.4)
        );
        let o = file(v95, 0.0, 1.2, -0.1);
        assert_eq!(
            (o.shape, o.width, o.length, o.height),
            (S::CylinderC0, 0.1, 1.2, 0.1)
        );
        let o = file(v95, 0.8, 0.0, -0.1);
        assert_eq!(
            (o.shape, o.width, o.length, o.height),
            (S::CylinderC90, 0.8, 0.1, 0.1)
        );
        assert_eq!(file(v95, -0.1, 1.2, -0.2).shape, S::Ellipsoid);
        assert_eq!(file(v95, -1.0, 0.0, 1.92).shape, S::Ellipse);
    }

    /// Files as old tools wrote them: a 1986 label line beginning with
    /// `TILT` but no `=` (`TILTED FLOOD`, taken for the TILT line before),
    /// lone-CR line ends (old Mac OS: one line before) and a DOS
    /// end-of-file mark, Ctrl-Z, after the data (refused as data before).
    /// Each reads as its LF twin does.
    #[test]
    fn old_line_ends_labels_and_end_of_file_marks() {
        let lf = "TILTED FLOOD\nTILT=NONE\n1 1000 2 3 1\n1 2 0 0 0 0.5\n3 10 0 45\n90 0 4 5\n6\n";
        let want = parse(lf, "a.ies").unwrap();
        assert_eq!(want.candela[0], [12.0, 15.0, 18.0]);
        for text in [
            lf.replace('\n', "\r"),
            lf.replace('\n', "\r\n"),
            format!("{lf}\u{1a}"),
            format!("{}\u{1a}", lf.replace('\n', "\r\n")),
        ] {
            assert_eq!(parse(&text, "a.ies").unwrap(), want, "{text:?}");
        }
    }

    #[test]
    fn versions_multipliers_and_wrapped_numbers() {
        // 1986 (no header), numbers wrapped anywhere, commas as separators,
        // multiplier 2, ballast 0.5, ballast-lamp factor 3 (applied before 2002).
        let f86 = "label line\nTILT=NONE\n1 1000 2 3 1\n1 2 0 0 0 0.5\n3 10 0,45\n90 0 4 5\n6\n";
        let p = parse(f86, "a.ies").unwrap();
        assert_eq!(p.format, "IES LM-63-1986");
        assert_eq!(p.v_angles, [0.0, 45.0, 90.0]);
        assert_eq!(p.candela[0], [12.0, 15.0, 18.0]);
        assert_eq!(p.opening, Opening::default());
        // 1995 and 2002: the second factor is "future use" (0.0001 here,
        // or 0, which a factor could not be); 2019: the file generation
        // type. None multiplies.
        for (head, fmt, second) in [
            ("IESNA:LM-63-1995", "IES LM-63-1995", "0.0001"),
            ("IESNA:LM-63-1995", "IES LM-63-1995", "0"),
            ("IESNA:LM-63-2002", "IES LM-63-2002", "1.10001"),
            ("IES:LM-63-2019", "IES LM-63-2019", "1.10001"),
        ] {
            let f = format!(
                "{head}\n[TEST] x\nTILT=NONE\n1 -1 2 3 1 1 2 0 0 0\n0.5 {second} 10\n0 45 90 0\n4 5 6\n"
            );
            let p = parse(&f, "b.ies").unwrap();
            assert_eq!(p.format, fmt);
            assert_eq!(p.candela[0], [4.0, 5.0, 6.0]);
            assert_eq!(p.lamp_lumens, None);
        }
        // 1991: the ballast-lamp photometric factor (3) multiplies.
        let f = "IESNA91\n[TEST] x\nTILT=NONE\n1 -1 2 3 1 1 2 0 0 0\n0.5 3 10\n0 45 90 0\n4 5 6\n";
        assert_eq!(parse(f, "b.ies").unwrap().candela[0], [12.0, 15.0, 18.0]);
        // TILT=INCLUDE: the table is kept, not applied; upright (tilt 0)
        // its factor is 0.5.
        let f = "IESNA91\nTILT=INCLUDE\n1\n3\n-10 0 10\n0.8 0.5 0.8\n1 100 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n2 4\n";
        let p = parse(f, "c.ies").unwrap();
        assert_eq!(p.candela[0], [2.0, 4.0]);
        let tilt = p.tilt.as_ref().unwrap();
        assert_eq!(tilt.geometry, TiltGeometry::Vertical);
        assert_eq!(
            (&tilt.angles[..], &tilt.factors[..]),
            (&[-10.0, 0.0, 10.0][..], &[0.8, 0.5, 0.8][..])
        );
        assert_eq!(p.upright_tilt_factor(), 0.5);
        // Linear between angles, the end factor beyond: 5 deg half way, 30 clamped.
        assert_eq!(tilt.factor(5.0), 0.65);
        assert_eq!(tilt.factor(30.0), 0.8);
        assert_eq!(tilt.factor(-30.0), 0.8);
    }

    /// A byte-order mark or blank lines before the version line (the
    /// reviewer's `bom.ies`, an LM-63-2019 file whose file-generation type
    /// 1.10001 must not multiply): the same table as without, the file's
    /// own values 100, 80, 50 cd; read from disk (the BOM's UTF-8 bytes) and
    /// from text (U+FEFF).
    #[test]
    fn a_byte_order_mark_or_blank_lines_do_not_hide_the_version() {
        let body = "IES:LM-63-2019\n[TEST] x\n[TESTLAB] y\n[ISSUEDATE] 2020\n[MANUFAC] z\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1.10001 50\n0 45 90\n0\n100 80 50\n";
        let dir = tempfile::tempdir().unwrap();
        let mut variants = Vec::new();
        for (name, text) in [
            ("nobom.ies", body.to_string()),
            ("bom.ies", format!("\u{feff}{body}")),
            ("blank.ies", format!("\n  \r\n\t\n{body}")),
            ("bomblank.ies", format!("\u{feff}\n{body}")),
        ] {
            let path = dir.path().join(name);
            std::fs::write(&path, text.as_bytes()).unwrap();
            variants.push((name, super::super::read(&path).unwrap()));
            variants.push((name, parse(&text, name).unwrap()));
        }
        for (name, p) in &variants {
            assert_eq!(p.format, "IES LM-63-2019", "{name}");
            assert_eq!(p.candela, [vec![100.0, 80.0, 50.0]], "{name}");
            assert_eq!(p.watts, Some(50.0), "{name}");
        }
        // Line numbers still count the blank lines: the bad value is on line 14.
        let bad = format!("\u{feff}\n\n\n{}", body.replace("100 80 50", "100 -80 50"));
        let e = parse(&bad, "b.ies").unwrap_err();
        assert_eq!((e.line, e.field.as_str()), (14, "candela values"), "{e}");
    }

    #[test]
    fn errors_name_line_and_field() {
        let cases = [
            ("IESNA:LM-63-1995\nTILT=lamp.tlt\n", 2, "TILT"),
            ("IESNA:LM-63-1995\n[TEST]\n", 0, "TILT"),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n1 2\n",
                7,
                "candela value at horizontal angle 0",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 3 1 4 2 0 0 0\n",
                3,
                "photometric type",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 10\n0 90 45\n0\n1 2 3\n",
                5,
                "vertical angles",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1 1 10\n0 45 90\n0\n1 -2 3\n",
                7,
                "candela values",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 3 2 1 2 0 0 0\n1 1 10\n0 45 90\n0 45\n1 2 3\n1 2 3\n",
                6,
                "horizontal angles",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 2 1 1 2 0 0 0\n1 1 10\n0 90\n0\n1 2 3\n",
                7,
                "end of file",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1000 1 99999 99999 1 2 0 0 0\n",
                3,
                "number of angles",
            ),
            (
                "IESNA:LM-63-1995\nTILT=NONE\n1 1e999 1 2 1 1 2 0 0 0\n",
                3,
                "lumens per lamp",
            ),
        ];
        for (text, line, field) in cases {
            let e = parse(text, "x.ies").unwrap_err();
            assert_eq!((e.line, e.field.as_str()), (line, field), "{e}");
            // Line 0 (the file as a whole) is not printed.
            let at = if line > 0 {
                format!(":{line}")
            } else {
                String::new()
            };
            assert!(
                e.to_string().starts_with(&format!("x.ies{at}: {field}: ")),
                "{e}"
            );
        }
    }

    #[test]
    fn no_panic_on_any_prefix_or_byte_flip() {
        // Every prefix of a valid file and every single-byte corruption of
        // it gives Ok or an error, never a panic.
        let text = PENDANT;
        for n in 0..text.len() {
            if text.is_char_boundary(n) {
                let _ = parse(&text[..n], "p.ies");
            }
        }
        let bytes = text.as_bytes();
        for (k, b) in [b'-', b'9', b'x', b' ', b'\n', b'.', b'e']
            .iter()
            .enumerate()
        {
            for i in (k..bytes.len()).step_by(7) {
                let mut v = bytes.to_vec();
                v[i] = *b;
                let s: String = v.iter().map(|&c| c as char).collect();
                let _ = parse(&s, "p.ies");
            }
        }
    }
}
