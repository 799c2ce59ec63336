//! Photometric files of luminaires: IES LM-63 ([`ies`]) and EULUMDAT
//! ([`ldt`]), parsed into one [`Photometry`] record. Formats only: the
//! interpolated distribution and its sampler live in `light`.
//!
//! Both parsers are written here (the one crate that reads both formats is
//! AGPL-3.0 and extrapolates beyond the measured angles; another fails on
//! 1986-style files and wrapped TILT data: see `shared/design/CRATES.md`).
//! Neither panics on any input: every error names the file, the line and
//! the field.

pub mod ies;
pub mod ldt;

/// How the angles of a photometric table are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotometricType {
    /// Type C: vertical angles `gamma` from the nadir (0) to the zenith
    /// (180) in C-planes about the luminaire's vertical axis (indoor and
    /// road luminaires; EULUMDAT is always type C).
    C,
    /// Type B: the polar axis is the luminaire's horizontal (transverse)
    /// axis (floodlights).
    B,
    /// Type A: the polar axis is the luminaire's longitudinal axis (automotive).
    A,
}

/// Luminous opening of the luminaire [m]: a rectangle `width x length`, or
/// a disc of diameter `width` when `round`; `height` of the luminous sides.
/// All zero: a point source.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Opening {
    /// Width [m] (diameter when `round`).
    pub width: f64,
    /// Length [m] (0 when `round`).
    pub length: f64,
    /// Height of the luminous sides [m].
    pub height: f64,
    /// A circular opening.
    pub round: bool,
}

/// A luminaire's measured intensity distribution, as read from the file.
///
/// `candela[i][k]` is the intensity [cd] in horizontal plane `h_angles[i]`
/// at vertical angle `v_angles[k]` (degrees, both ascending), with every
/// multiplier of the file already applied. The table covers only the
/// planes the file stores; [`Photometry::symmetry`] says how the others
/// follow from them (the distribution module expands it).
#[derive(Clone, Debug, PartialEq)]
pub struct Photometry {
    /// Layout of the angles.
    pub kind: PhotometricType,
    /// Vertical angles [deg], ascending.
    pub v_angles: Vec<f64>,
    /// Horizontal angles [deg], ascending.
    pub h_angles: Vec<f64>,
    /// Intensity [cd] per horizontal plane, per vertical angle.
    pub candela: Vec<Vec<f64>>,
    /// Rated lamp flux [lm] of the lamps the table refers to; `None` for
    /// absolute photometry (the table is the luminaire's own).
    pub lamp_lumens: Option<f64>,
    /// Luminous opening [m].
    pub opening: Opening,
    /// Input power [W], where the file gives one.
    pub watts: Option<f64>,
    /// Format and version, e.g. `IES LM-63-1995`, `EULUMDAT`.
    pub format: String,
}

/// Horizontal symmetry of a type C table, by the planes it stores.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Symmetry {
    /// One plane: the same in every C-plane.
    Rotational,
    /// C0-C90: mirrored about C0-C180 and about C90-C270.
    Quadrant,
    /// C0-C180: mirrored about the C0-C180 plane.
    BilateralC0,
    /// C90-C270: mirrored about the C90-C270 plane.
    BilateralC90,
    /// C0-C360 (the last plane may repeat the first).
    None,
}

impl Photometry {
    /// The symmetry of a type C table, from its first and last horizontal angle.
    pub fn symmetry(&self) -> Symmetry {
        let (first, last) = (
            self.h_angles.first().copied().unwrap_or(0.0),
            self.h_angles.last().copied().unwrap_or(0.0),
        );
        if self.h_angles.len() == 1 {
            Symmetry::Rotational
        } else if first == 90.0 && last == 270.0 {
            Symmetry::BilateralC90
        } else if last == 90.0 {
            Symmetry::Quadrant
        } else if last == 180.0 {
            Symmetry::BilateralC0
        } else {
            Symmetry::None
        }
    }

    /// Largest intensity in the table [cd].
    pub fn max_candela(&self) -> f64 {
        self.candela
            .iter()
            .flatten()
            .fold(0.0, |m: f64, &c| m.max(c))
    }
}

/// An error in a photometric file, naming the file, the line and the field.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("{file}{}: {field}: {message}", if *line > 0 { format!(":{line}") } else { String::new() })]
pub struct PhotometryError {
    /// The file, as given.
    pub file: String,
    /// 1-based line number (0: the file as a whole).
    pub line: usize,
    /// The field, in the format's own words.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

/// Read a photometric file by its extension: `.ies` or `.ldt` (any case).
pub fn read(path: &std::path::Path) -> Result<Photometry, PhotometryError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| PhotometryError {
        file: name.clone(),
        line: 0,
        field: "file".into(),
        message: format!("cannot read: {e}"),
    })?;
    // Photometric files are often Latin-1: keep every byte as a character.
    let text: String = bytes.iter().map(|&b| b as char).collect();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("ies") => ies::parse(&text, &name),
        Some("ldt") => ldt::parse(&text, &name),
        _ => Err(PhotometryError {
            file: name,
            line: 0,
            field: "file".into(),
            message: "unknown photometric format: the name must end in .ies or .ldt".into(),
        }),
    }
}

/// Check that angles are finite, ascending and within `[lo, hi]` degrees.
pub(crate) fn check_angles(
    angles: &[f64],
    lo: f64,
    hi: f64,
    err: impl Fn(String) -> PhotometryError,
) -> Result<(), PhotometryError> {
    for (k, &a) in angles.iter().enumerate() {
        if !(a.is_finite() && (lo..=hi).contains(&a)) {
            return Err(err(format!(
                "angle {} = {} lies outside [{lo}, {hi}] degrees",
                k + 1,
                crate::io::format_number(a)
            )));
        }
        if k > 0 && a <= angles[k - 1] {
            return Err(err(format!(
                "angles must ascend: angle {} = {} after {}",
                k + 1,
                crate::io::format_number(a),
                crate::io::format_number(angles[k - 1])
            )));
        }
    }
    Ok(())
}

/// `v` as a whole number in `lo..=hi`, or the message saying why not.
pub(crate) fn whole(v: f64, lo: i64, hi: i64) -> Result<i64, String> {
    if v.fract() != 0.0 || v < lo as f64 || v > hi as f64 {
        Err(format!(
            "must be a whole number in [{lo}, {hi}], got {}",
            crate::io::format_number(v)
        ))
    } else {
        Ok(v as i64)
    }
}
