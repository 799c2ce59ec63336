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

/// The shape of a luminous opening, as IES LM-63-2002 (Table 1, "luminous
/// shapes") encodes it in the signs of width, length and height; the LM-63
/// names in [`OpeningShape::name`]. Axes: the length along the C0-C180
/// plane (the "photometric horizontal", local `x`), the width along
/// C90-C270 (local `y`), the height vertical (local `z`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OpeningShape {
    /// No luminous opening (all dimensions zero).
    #[default]
    Point,
    /// A rectangle `length x width` facing down (the nadir), with luminous
    /// sides `height` tall (0: none). LM-63: all positive; EULUMDAT: a
    /// length and a width.
    Rectangle,
    /// An ellipse facing down with diameters `length` (C0) and `width`
    /// (C90) (a circle when equal), with luminous sides `height` tall (a
    /// vertical circular or elliptical cylinder; 0: none). LM-63-2002:
    /// width and length negative, height positive or zero; EULUMDAT: a
    /// diameter.
    Ellipse,
    /// An ellipsoid with diameters `length`, `width` and `height` (a sphere
    /// when equal), luminous all over. LM-63-2002: all three negative.
    Ellipsoid,
    /// A horizontal circular or elliptical cylinder along C0-C180, `length`
    /// long, its cross-section an ellipse of diameters `width` and
    /// `height`, luminous all over (ends included). LM-63-2002: width and
    /// height negative, length positive.
    CylinderC0,
    /// A horizontal cylinder along C90-C270, `width` long, its
    /// cross-section an ellipse of diameters `length` and `height`.
    /// LM-63-2002: length and height negative, width positive.
    CylinderC90,
    /// A vertical circle or ellipse facing C0 and C180 (both faces
    /// luminous), of diameters `width` and `height`. LM-63-2002: width and
    /// height negative, length zero.
    VerticalEllipseC0,
    /// A vertical circle or ellipse facing C90 and C270, of diameters
    /// `length` and `height`. LM-63-2002: length and height negative,
    /// width zero.
    VerticalEllipseC90,
}

impl OpeningShape {
    /// The LM-63-2002 name of the shape with these dimensions \[m\] (circle,
    /// cylinder, sphere where the diameters agree to 1e-9 relative).
    pub fn name(self, width: f64, length: f64, height: f64) -> &'static str {
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        // An ellipse's length 0 means "as wide as it is long" (a circle).
        let length = if self == OpeningShape::Ellipse && length == 0.0 {
            width
        } else {
            length
        };
        match self {
            OpeningShape::Point => "point",
            OpeningShape::Rectangle if height > 0.0 => "rectangular with luminous sides",
            OpeningShape::Rectangle => "rectangular",
            OpeningShape::Ellipse => match (same(width, length), height > 0.0) {
                (true, false) => "circular",
                (false, false) => "ellipse",
                (true, true) => "vertical cylinder",
                (false, true) => "vertical elliptical cylinder",
            },
            OpeningShape::Ellipsoid if same(width, length) && same(width, height) => "sphere",
            OpeningShape::Ellipsoid => "ellipsoidal spheroid",
            OpeningShape::CylinderC0 if same(width, height) => {
                "horizontal cylinder along photometric horizontal"
            }
            OpeningShape::CylinderC0 => {
                "horizontal elliptical cylinder along photometric horizontal"
            }
            OpeningShape::CylinderC90 if same(length, height) => {
                "horizontal cylinder perpendicular to photometric horizontal"
            }
            OpeningShape::CylinderC90 => {
                "horizontal elliptical cylinder perpendicular to photometric horizontal"
            }
            OpeningShape::VerticalEllipseC0 if same(width, height) => {
                "vertical circle facing photometric horizontal"
            }
            OpeningShape::VerticalEllipseC0 => "vertical ellipse facing photometric horizontal",
            OpeningShape::VerticalEllipseC90 if same(length, height) => {
                "vertical circle facing perpendicular to photometric horizontal"
            }
            OpeningShape::VerticalEllipseC90 => {
                "vertical ellipse facing perpendicular to photometric horizontal"
            }
        }
    }
}

/// Luminous opening of the luminaire: its [`OpeningShape`] and the three
/// dimensions \[m\] (all >= 0) that the shape gives meaning to. The
/// rectangle and the disc (`round`) keep their older reading: a rectangle
/// `width x length` or a disc of diameter `width` (its `length` 0), each
/// with luminous sides `height` tall. All zero: a point source.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Opening {
    /// Width \[m\], along C90-C270 (the diameter of a disc).
    pub width: f64,
    /// Length \[m\], along C0-C180 (0 for a disc: as long as it is wide).
    pub length: f64,
    /// Height \[m\]: of the luminous sides of a rectangle or an ellipse (0:
    /// none); a diameter of the other shapes.
    pub height: f64,
    /// A circular or elliptical opening facing down (`shape` is
    /// [`OpeningShape::Ellipse`]).
    pub round: bool,
    /// The shape.
    pub shape: OpeningShape,
}

/// How the lamp sits in the luminaire (IES LM-63 "lamp-to-luminaire
/// geometry"): what the angles of a `TILT=INCLUDE` table measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TiltGeometry {
    /// 1: the lamp vertical, base up or down: the tilt is the angle [deg,
    /// 0-180] between the photometric nadir (the light's `aim`) and
    /// straight down (world `-z`).
    Vertical,
    /// 2: the lamp horizontal, its axis along the C0-C180 plane (local
    /// `x`): the tilt is the inclination [deg, 0-90] of local `x` from the
    /// horizontal.
    HorizontalC0,
    /// 3: the lamp horizontal, its axis along C90-C270 (local `y`): the
    /// inclination [deg, 0-90] of local `y` from the horizontal.
    HorizontalC90,
}

/// An IES `TILT=INCLUDE` table: the factor by which the lamp's output
/// changes with the luminaire's tilt from its measured position (upright:
/// nadir down, C0 and C90 horizontal, tilt 0 in every geometry). The
/// factor at the installed tilt multiplies every intensity, and so the
/// flux (applied where a light is placed: `scene` compile).
#[derive(Clone, Debug, PartialEq)]
pub struct Tilt {
    /// What the angles measure.
    pub geometry: TiltGeometry,
    /// Tilt angles \[deg\], ascending, within [-180, 180].
    pub angles: Vec<f64>,
    /// Multiplying factors (>= 0) at `angles`.
    pub factors: Vec<f64>,
}

impl Tilt {
    /// The tilt \[deg\] of a luminaire whose local axes `x` (C0), `y` (C90)
    /// and `z` (opposite the nadir) are the given world unit vectors (world
    /// `z` up), by [`Self::geometry`]: 0-180 for
    /// [`TiltGeometry::Vertical`], 0-90 for the horizontal lamps.
    pub fn angle(&self, x: glam::DVec3, y: glam::DVec3, z: glam::DVec3) -> f64 {
        // The angle of v from the horizontal plane, 0-90 (atan2: accurate
        // near both ends, unlike asin / acos).
        let inclination = |v: glam::DVec3| v.z.abs().atan2(v.x.hypot(v.y)).to_degrees();
        match self.geometry {
            // Between the nadir -z and world -z: that of z and world +z.
            TiltGeometry::Vertical => z.x.hypot(z.y).atan2(z.z).to_degrees(),
            TiltGeometry::HorizontalC0 => inclination(x),
            TiltGeometry::HorizontalC90 => inclination(y),
        }
    }

    /// The factor at tilt `angle` \[deg\]: linear in the angle between the
    /// table's angles, the end factors beyond them (clamped, never
    /// extrapolated).
    pub fn factor(&self, angle: f64) -> f64 {
        let (xs, ys) = (&self.angles, &self.factors);
        let k = xs.partition_point(|&a| a <= angle);
        if k == 0 {
            return ys[0];
        }
        if k == xs.len() {
            return ys[xs.len() - 1];
        }
        let t = (angle - xs[k - 1]) / (xs[k] - xs[k - 1]);
        ys[k - 1] + t * (ys[k] - ys[k - 1])
    }
}

/// A luminaire's measured intensity distribution, as read from the file.
///
/// `candela[i][k]` is the intensity \[cd\] in horizontal plane `h_angles[i]`
/// at vertical angle `v_angles[k]` (degrees, both ascending), with every
/// multiplier of the file already applied except the tilt factor, which
/// depends on how the luminaire is installed ([`Photometry::tilt_factor`]).
/// The table covers only the
/// planes the file stores; [`Photometry::symmetry`] says how the others
/// follow from them (the distribution module expands it).
#[derive(Clone, Debug, PartialEq)]
pub struct Photometry {
    /// Layout of the angles.
    pub kind: PhotometricType,
    /// Vertical angles \[deg\], ascending.
    pub v_angles: Vec<f64>,
    /// Horizontal angles \[deg\], ascending.
    pub h_angles: Vec<f64>,
    /// Intensity \[cd\] per horizontal plane, per vertical angle.
    pub candela: Vec<Vec<f64>>,
    /// Rated lamp flux \[lm\] of the lamps the table refers to; `None` for
    /// absolute photometry (the table is the luminaire's own).
    pub lamp_lumens: Option<f64>,
    /// Luminous opening \[m\].
    pub opening: Opening,
    /// Input power \[W\], where the file gives one.
    pub watts: Option<f64>,
    /// Format and version, e.g. `IES LM-63-1995`, `EULUMDAT`.
    pub format: String,
    /// The IES `TILT=INCLUDE` table (`None`: `TILT=NONE`, and EULUMDAT).
    pub tilt: Option<Tilt>,
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
    /// A full turn from C0: the last plane may be C360 (repeating C0), or
    /// any angle past 180 (then the table wraps from it to C360 = C0).
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

    /// The tilt factor of the luminaire whose local axes `x` (C0), `y`
    /// (C90), `z` (opposite the nadir) are these world unit vectors ([`Tilt`];
    /// 1 without a tilt table), with the tilt \[deg\] it was read at (`None`
    /// without a table). The upright luminaire (`X`, `Y`, `Z`) has tilt 0.
    pub fn tilt_factor(
        &self,
        x: glam::DVec3,
        y: glam::DVec3,
        z: glam::DVec3,
    ) -> (f64, Option<f64>) {
        match &self.tilt {
            Some(t) => {
                let a = t.angle(x, y, z);
                (t.factor(a), Some(a))
            }
            None => (1.0, None),
        }
    }

    /// The tilt factor of the upright luminaire (nadir down, C0 along `x`):
    /// the table as measured, for summaries and plots of the file itself.
    pub fn upright_tilt_factor(&self) -> f64 {
        self.tilt_factor(glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z)
            .0
    }

    /// Largest intensity in the table \[cd\].
    pub fn max_candela(&self) -> f64 {
        self.candela
            .iter()
            .flatten()
            .fold(0.0, |m: f64, &c| m.max(c))
    }
}

/// An error in a photometric file, naming the file, the line and the field.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error(
    "{file}{}: {}{message}",
    if *line > 0 { format!(":{line}") } else { String::new() },
    if field.is_empty() { String::new() } else { format!("{field}: ") }
)]
pub struct PhotometryError {
    /// The file, as given.
    pub file: String,
    /// 1-based line number (0: the file as a whole).
    pub line: usize,
    /// The field, in the format's own words (empty: the file as a whole).
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
        field: String::new(),
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

/// `text` without a leading byte-order mark: `U+FEFF`, or its UTF-8 bytes
/// `EF BB BF` as [`read`] decodes them (one Latin-1 character per byte).
/// Editors on Windows write one; left in place it would hide an IES file's
/// version line.
/// The lines of a photometric file's text: a byte-order mark skipped
/// ([`strip_bom`]), the text ended at a DOS end-of-file mark (Ctrl-Z,
/// 0x1A, which files from DOS tools often end with), and lines ended by
/// LF or CR LF, or in a file without any LF by a lone CR (old Mac OS
/// files; a stray CR elsewhere stays, as trailing white space of its line).
pub(crate) fn text_lines(text: &str) -> Vec<&str> {
    let text = strip_bom(text);
    let text = text.find('\u{1a}').map_or(text, |i| &text[..i]);
    if text.contains('\n') {
        text.lines().collect()
    } else {
        text.split_terminator('\r').collect()
    }
}

pub(crate) fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}')
        .or_else(|| text.strip_prefix("\u{ef}\u{bb}\u{bf}"))
        .unwrap_or(text)
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
