//! Bad and unusual inputs on every channel (issue 12, "Done when"): scene
//! TOML, points and views CSV, OBJ meshes, SH coefficient files, IES and
//! EULUMDAT files, and the command line. Each case records the outcome it
//! must have (refused with a message naming the file, line and field, or
//! run with a given warning or flag, or run with the same answer as the
//! plain input, or run with a given answer); every case is run against the
//! built binary and must also neither panic nor put a NaN or an infinity in
//! any output.
//!
//! `validation/bad_inputs.md` lists every case and what it gets now; this
//! test fails when that file differs from what the runs give (rewrite it
//! with `LUMEST_BLESS=1 cargo test --release --test bad_inputs`).

#[path = "bad_inputs/harness.rs"]
mod harness;

use harness::*;
use std::collections::BTreeMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

fn text(t: impl Into<String>) -> Body {
    Body::Text(t.into())
}

fn case(ch: Ch, what: &str, body: Body, expect: Expect) -> Case {
    Case {
        ch,
        what: what.to_string(),
        body,
        args: Vec::new(),
        expect,
        stdin: None,
    }
}

/// The plain scene with `extra` appended.
fn scene_add(what: &str, extra: &str, expect: Expect) -> Case {
    case(Ch::Scene, what, text(format!("{SCENE}\n{extra}")), expect)
}

/// The plain scene with `from` replaced by `to`.
fn scene_rep(what: &str, from: &str, to: &str, expect: Expect) -> Case {
    assert!(SCENE.contains(from), "{what}: `{from}` not in the scene");
    case(Ch::Scene, what, text(SCENE.replacen(from, to, 1)), expect)
}

/// A `[[surface]]` of `kind` with `body` appended to the plain scene.
fn surface(what: &str, kind: &str, body: &str, expect: Expect) -> Case {
    scene_add(
        what,
        &format!("[[surface]]\ntype = \"{kind}\"\n{body}\n"),
        expect,
    )
}

/// A `[[light]]` of `kind` with `body` appended to the plain scene.
fn light(what: &str, kind: &str, body: &str, expect: Expect) -> Case {
    scene_add(
        what,
        &format!("[[light]]\ntype = \"{kind}\"\n{body}\n"),
        expect,
    )
}

const LAMB: &str = "material = { type = \"lambertian\", reflectance = 0.5 }";

fn points(what: &str, t: &str, expect: Expect) -> Case {
    case(Ch::Points, what, text(t), expect)
}

fn views(what: &str, t: &str, expect: Expect) -> Case {
    case(Ch::Views, what, text(t), expect)
}

fn obj(what: &str, t: &str, expect: Expect) -> Case {
    case(Ch::Obj, what, text(t), expect)
}

fn sh(what: &str, t: &str, expect: Expect) -> Case {
    case(Ch::Sh, what, text(t), expect)
}

fn ies(what: &str, t: &str, expect: Expect) -> Case {
    case(Ch::Ies, what, text(t), expect)
}

/// The plain IES file with line `n` (1-based) replaced.
fn ies_line(what: &str, n: usize, line: &str, expect: Expect) -> Case {
    let mut l: Vec<&str> = IES.lines().collect();
    l[n - 1] = line;
    ies(what, &(l.join("\n") + "\n"), expect)
}

/// The plain EULUMDAT file with line `n` (1-based) replaced.
fn ldt_line(what: &str, n: usize, line: &str, expect: Expect) -> Case {
    let base = ldt();
    let mut l: Vec<&str> = base.lines().collect();
    l[n - 1] = line;
    case(Ch::Ldt, what, text(l.join("\n") + "\n"), expect)
}

fn cli(what: &str, args: &str, expect: Expect) -> Case {
    Case {
        ch: Ch::Cli,
        what: what.to_string(),
        body: Body::Missing,
        args: args.split_whitespace().map(str::to_string).collect(),
        expect,
        stdin: None,
    }
}

/// `illuminance` on the plain files with `extra` options.
fn ill(what: &str, extra: &str, expect: Expect) -> Case {
    cli(
        what,
        &if extra.contains("--out") {
            format!("illuminance --scene {{s}} --points {{p}} --quiet {extra}")
        } else {
            format!("illuminance --scene {{s}} --points {{p}} --out {{d}}/E.csv --quiet {extra}")
        },
        expect,
    )
}

/// `luminance` on the plain files with `extra` options.
fn lum(what: &str, extra: &str, expect: Expect) -> Case {
    cli(
        what,
        &if extra.contains("--out") {
            format!("luminance --scene {{s}} --quiet {extra}")
        } else {
            format!("luminance --scene {{s}} --out {{d}}/L.csv --quiet {extra}")
        },
        expect,
    )
}

/// `render` of the plain scene, 4 x 3 pixels, with `extra` options.
fn render(what: &str, extra: &str, expect: Expect) -> Case {
    cli(
        what,
        &format!(
            "render --scene {{s}} {}--chains 1024 --batch-size 32 --quiet {extra}",
            if extra.contains("--width") || extra.contains("--height") {
                ""
            } else {
                "--width 4 --height 3 "
            }
        ),
        expect,
    )
}

use Expect::{Accept, Error, Flag, Same, Warn};

fn scene_cases() -> Vec<Case> {
    let mut c = vec![
        case(Ch::Scene, "empty file", text(""), Error("the scene has no [[light]]")),
        case(Ch::Scene, "file missing", Body::Missing, Error("cannot read scene file")),
        case(Ch::Scene, "a folder instead of a file", Body::Folder, Error("cannot read scene file")),
        case(
            Ch::Scene,
            "not UTF-8 (Latin-1 byte in a name)",
            Body::Bytes([SCENE.as_bytes(), b"# \xe4\n"].concat()),
            Error("not UTF-8 text"),
        ),
        case(Ch::Scene, "not TOML at all", text("this is not a scene\n"), Error("s.toml:1:")),
        case(Ch::Scene, "byte-order mark before the first table", text(format!("\u{feff}{SCENE}")), Same),
        case(Ch::Scene, "CRLF line ends", text(SCENE.replace('\n', "\r\n")), Same),
        case(Ch::Scene, "comments and blank lines everywhere", text(SCENE.replace('\n', "  # note\n\n")), Same),
        scene_add("unknown key", "lumens = 1\n", Error("unknown field `lumens`")),
        scene_add("`[surface]` after `[[surface]]` (single brackets)", "[surface]\ntype = \"plane\"\n", Error("write `[[surface]]` with double brackets")),
        case(
            Ch::Scene,
            "`[surface]` as the only surface (single brackets)",
            text(SCENE.replace("[[surface]]", "[surface]")),
            Error("s.toml:1:1: invalid type: map, expected a sequence (each surface is an array-of-tables entry: write `[[surface]]` with double brackets)"),
        ),
        scene_add("`[light]` after `[[light]]` (single brackets)", "[light]\ntype = \"point\"\n", Error("write `[[light]]` with double brackets")),
        scene_rep("duplicate key in a table", "intensity = 100.0", "intensity = 100.0\nintensity = 50.0", Error("duplicate key `intensity`")),
        scene_rep("unknown key in a surface", "name = \"room\"", "name = \"room\"\ncolour = \"red\"", Error("unknown field `colour`")),
        scene_rep("unknown key in a light", "name = \"lamp\"", "name = \"lamp\"\nwatts = 60", Error("unknown field `watts`")),
        scene_rep("unknown key in a material", "reflectance = 0.5 }", "reflectance = 0.5, gloss = 1 }", Error("unknown field `gloss`")),
        scene_rep("surface without `type`", "type = \"box\"\n", "", Error("missing field `type`")),
        scene_rep("unknown surface type", "type = \"box\"", "type = \"cube\"", Error("`cube`")),
        scene_rep("unknown light type", "type = \"point\"", "type = \"laser\"", Error("`laser`")),
        scene_rep("light type in capitals", "type = \"point\"", "type = \"Point\"", Error("`Point`")),
        scene_rep("no lights", "[[light]]\nname = \"lamp\"\ntype = \"point\"\nposition = [0, 0, 2.5]\nintensity = 100.0\n", "", Error("the scene has no [[light]]")),
        case(
            Ch::Scene,
            "a light and no surfaces",
            text("[[light]]\ntype = \"point\"\nposition = [0, 0, 2.5]\nintensity = 100.0\n"),
            Accept("E_avg 22.5192 lx"),
        ),
        // Far from the origin for its size: warned (steps off surfaces are
        // 1e-8 of the coordinates, 6.4 cm at 6.4e6 m).
        case(
            Ch::Scene,
            "a small scene 6.4e6 m from the origin",
            text("[[surface]]\ntype = \"sphere\"\ncenter = [6.4e6, 0, 0]\nradius = 1\n\
                  material = { type = \"lambertian\", reflectance = 0.5 }\n\n\
                  [[light]]\ntype = \"point\"\nposition = [6.4e6, 0, 2]\nintensity = 100.0\n"),
            Accept("WARNING: the scene lies up to 6.400e6 m from the origin"),
        ),
        scene_rep("intensity as a string", "intensity = 100.0", "intensity = \"100\"", Error("field `intensity`")),
        scene_rep("intensity as an integer", "intensity = 100.0", "intensity = 100", Same),
        scene_rep("intensity as a boolean", "intensity = 100.0", "intensity = true", Error("field `intensity`")),
        scene_rep("intensity as an array", "intensity = 100.0", "intensity = [100.0]", Error("field `intensity`")),
        scene_rep("intensity nan", "intensity = 100.0", "intensity = nan", Error("field `intensity`: must be finite")),
        scene_rep("intensity inf", "intensity = 100.0", "intensity = inf", Error("field `intensity`: must be finite")),
        scene_rep("intensity -inf", "intensity = 100.0", "intensity = -inf", Error("field `intensity`: must be finite")),
        scene_rep("intensity negative", "intensity = 100.0", "intensity = -1.0", Error("field `intensity`: must be finite and >= 0, got -1")),
        scene_rep("intensity -1e300 (shown short)", "intensity = 100.0", "intensity = -1e300", Error("got -1e300")),
        scene_rep("intensity 1e300 (above the limit)", "intensity = 100.0", "intensity = 1e300", Error("field `intensity`")),
        scene_rep("intensity 1e-300 (below the limit)", "intensity = 100.0", "intensity = 1e-300", Error("field `intensity`")),
        scene_rep("intensity 1e400 (overflows TOML)", "intensity = 100.0", "intensity = 1e400", Error("s.toml:")),
        scene_rep("intensity 0: nothing emits", "intensity = 100.0", "intensity = 0.0", Warn("WARNING: no light reaches any point")),
        scene_rep("intensity 1e50 (answers scale)", "intensity = 100.0", "intensity = 1e50", Accept("E_avg 4.4144e49 lx")),
        scene_rep("flux instead of intensity", "intensity = 100.0", "flux = 1256.6370614359173", Accept("E_avg 44.1439")),
        scene_rep("both intensity and flux", "intensity = 100.0", "intensity = 100.0\nflux = 10.0", Error("field `flux`: give either")),
        scene_rep("neither intensity nor flux", "intensity = 100.0", "", Error("field `intensity`: missing field")),
        scene_rep("flux negative", "intensity = 100.0", "flux = -5.0", Error("field `flux`")),
        scene_rep("position with two numbers", "position = [0, 0, 2.5]", "position = [0, 2.5]", Error("s.toml:")),
        scene_rep("position with four numbers", "position = [0, 0, 2.5]", "position = [0, 0, 2.5, 1]", Error("s.toml:")),
        // A decimal comma (`1,2` for 1.2) in an observer's or a grid's vector:
        // these were plain arrays, which dropped the extra number.
        scene_add("observer eye with four numbers (a decimal comma)", "[[observer]]\neye = [0.6, 1.4, 1,2]\nview = [1, 0, 0]\n", Error("invalid length 4, expected an array of 3 numbers")),
        scene_add("grid corner with four numbers (a decimal comma)", "[[grid]]\nname = \"g\"\ncorner = [-1, -1, 0,75]\nedge1 = [2, 0, 0]\nedge2 = [0, 2, 0]\n", Error("invalid length 4, expected an array of 3 numbers")),
        scene_rep("position as a string", "position = [0, 0, 2.5]", "position = \"0 0 2.5\"", Error("s.toml:")),
        scene_rep("position with a nan", "position = [0, 0, 2.5]", "position = [0, nan, 2.5]", Error("field `position`: every component must be finite")),
        scene_rep("position 1e13 m", "position = [0, 0, 2.5]", "position = [1e13, 0, 2.5]", Error("field `position`: every component must lie within")),
        scene_rep("position 1e300 m (shown short)", "position = [0, 0, 2.5]", "position = [1e300, 0, 2.5]", Error("1e300")),
        scene_rep("position missing", "position = [0, 0, 2.5]\n", "", Error("field `position`: missing field")),
        scene_rep("light outside the room", "position = [0, 0, 2.5]", "position = [0, 0, 5]", Warn("WARNING")),
        scene_rep("light exactly on the ceiling", "position = [0, 0, 2.5]", "position = [0, 0, 3]", Accept("E_avg")),
        scene_rep("light exactly on the floor", "position = [0, 0, 2.5]", "position = [0.5, 0.5, 0]", Accept("E_avg")),
        scene_rep("light in a corner of the room", "position = [0, 0, 2.5]", "position = [2, 2, 3]", Accept("E_avg")),
        scene_rep("light name empty", "name = \"lamp\"", "name = \"\"", Accept("E_avg 44.1439")),
        scene_rep("reflectance above 1", "reflectance = 0.5", "reflectance = 1.5", Error("field `reflectance`: must lie in [0, 1], got 1.5")),
        scene_rep("reflectance negative", "reflectance = 0.5", "reflectance = -0.1", Error("field `reflectance`")),
        scene_rep("reflectance nan", "reflectance = 0.5", "reflectance = nan", Error("field `reflectance`")),
        scene_rep("reflectance 1 everywhere in a closed room (infinite light)", "reflectance = 0.5", "reflectance = 1.0", Error("field `material`: every surface reflects all the light it receives")),
        case(
            Ch::Scene,
            "reflectance 1 on two parallel infinite planes (infinite light)",
            text("[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = { type = \"lambertian\", reflectance = 1 }\n[[surface]]\ntype = \"plane\"\npoint = [0, 0, 3]\nnormal = [0, 0, -1]\nmaterial = { type = \"phong\", diffuse = 0.5, specular = 0.5, exponent = 10 }\n[[light]]\ntype = \"point\"\nposition = [0, 0, 2.5]\nintensity = 100.0\n"),
            Error("every surface reflects all the light it receives"),
        ),
        case(
            Ch::Scene,
            "reflectance 1 on an open floor (light escapes)",
            text("[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\nmaterial = { type = \"lambertian\", reflectance = 1 }\n[[light]]\ntype = \"point\"\nposition = [0, 0, 2.5]\nintensity = 100.0\n"),
            Accept("E_avg"),
        ),
        case(
            Ch::Scene,
            "reflectance 1 in a closed room with a panel whose back absorbs",
            text(SCENE.replace("reflectance = 0.5", "reflectance = 1.0") + "[[surface]]\ntype = \"rectangle\"\ncorner = [-0.5, -0.5, 2.7]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"lambertian\", reflectance = 1 }\n"),
            Accept("E_avg"),
        ),
        scene_rep("reflectance 0: direct light only", "reflectance = 0.5", "reflectance = 0.0", Accept("E_avg 22.5")),
        scene_rep("reflectance as a percentage string", "reflectance = 0.5", "reflectance = \"50%\"", Error("s.toml:")),
        scene_rep("material missing", "material = { type = \"lambertian\", reflectance = 0.5 }\n", "", Error("field `material`: missing field")),
        scene_rep("material type unknown", "type = \"lambertian\"", "type = \"metal\"", Error("`metal`")),
        scene_rep("lambertian without reflectance", "type = \"lambertian\", reflectance = 0.5", "type = \"lambertian\"", Error("field `reflectance`")),
        scene_rep("lambertian with a Phong key", "reflectance = 0.5", "reflectance = 0.5, exponent = 3", Error("field `exponent`")),
        scene_rep("phong without specular", "type = \"lambertian\", reflectance = 0.5", "type = \"phong\", diffuse = 0.5, exponent = 10", Error("field `specular`")),
        scene_rep("phong kd + ks above 1", "type = \"lambertian\", reflectance = 0.5", "type = \"phong\", diffuse = 0.7, specular = 0.5, exponent = 10", Error("s.toml:6:")),
        scene_rep("phong exponent negative", "type = \"lambertian\", reflectance = 0.5", "type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = -1", Error("field `exponent`")),
        scene_rep("phong exponent 1e300 (a mirror)", "type = \"lambertian\", reflectance = 0.5", "type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = 1e300", Accept("E_avg")),
        scene_rep("phong exponent inf", "type = \"lambertian\", reflectance = 0.5", "type = \"phong\", diffuse = 0.3, specular = 0.2, exponent = inf", Error("field `exponent`")),
        scene_rep("phong specular negative", "type = \"lambertian\", reflectance = 0.5", "type = \"phong\", diffuse = 0.3, specular = -0.2, exponent = 5", Error("field `specular`")),
        // Plane.
        surface("glass: transmittance above a lossless pane's", "rectangle", "corner = [10, 10, 3]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"glass\", transmittance = 0.95 }", Error("field `transmittance`: must lie in [0, 0.918")),
        surface("glass: index below 1", "rectangle", "corner = [10, 10, 3]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"glass\", transmittance = 0.8, index = 0.5 }", Error("field `index`: must lie in [1, 5]")),
        surface("glass: transmittance missing", "rectangle", "corner = [10, 10, 3]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"glass\" }", Error("field `transmittance`: missing field")),
        surface("glass on a sphere", "sphere", "center = [10, 10, 3]\nradius = 1\nmaterial = { type = \"glass\", transmittance = 0.8 }", Error("only `rectangle` and `disc` surfaces take it")),
        surface("glass pane out of the way", "rectangle", "corner = [10, 10, 3]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"glass\", transmittance = 0.8 }", Accept("E_avg")),
        surface("glass pane through the lamp", "rectangle", "corner = [-0.5, -0.5, 2.5]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"glass\", transmittance = 0.8 }", Warn("WARNING: lamp lies in the plane of glass pane")),
        surface("plane: normal zero", "plane", &format!("point = [0, 0, 0]\nnormal = [0, 0, 0]\n{LAMB}"), Error("field `normal`: direction must have a non-zero length")),
        surface("plane: normal with nan", "plane", &format!("point = [0, 0, 0]\nnormal = [nan, 0, 1]\n{LAMB}"), Error("field `normal`")),
        // (Any non-zero length is a direction: scaled before it is normalised.)
        surface("plane: normal 1e-320 (denormal)", "plane", &format!("point = [0, 0, 0]\nnormal = [0, 0, 1e-320]\n{LAMB}"), Accept("E_avg")),
        surface("plane: point missing", "plane", &format!("normal = [0, 0, 1]\n{LAMB}"), Error("field `point`: missing field")),
        surface("plane: normal missing", "plane", &format!("point = [0, 0, 0]\n{LAMB}"), Error("field `normal`: missing field")),
        surface("plane: with a radius", "plane", &format!("point = [0, 0, 0]\nnormal = [0, 0, 1]\nradius = 1\n{LAMB}"), Error("field `radius`: not allowed")),
        surface("plane: coincides with the floor, facing down", "plane", &format!("point = [0, 0, 0]\nnormal = [0, 0, -1]\n{LAMB}"), Accept("E_avg")),
        scene_add(
            "65 infinite planes (64 at most)",
            &(0..65).map(|k| format!("[[surface]]\ntype = \"plane\"\npoint = [0, 0, {}]\nnormal = [0, 0, 1]\n{LAMB}\n", -1.0 - k as f64)).collect::<String>(),
            Error("at most 64 infinite planes"),
        ),
        // Rectangle.
        surface("rectangle: parallel edges", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [1, 0, 0]\nedge2 = [2, 0, 0]\n{LAMB}"), Error("s.toml:")),
        surface("rectangle: zero edge", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [0, 0, 0]\nedge2 = [0, 1, 0]\n{LAMB}"), Error("s.toml:")),
        surface("rectangle: edge2 missing", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [1, 0, 0]\n{LAMB}"), Error("field `edge2`: missing field")),
        surface("rectangle: sides = \"top\"", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nsides = \"top\"\n{LAMB}"), Error("field `sides`: must be one of")),
        surface("rectangle: with a radius", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nradius = 2\n{LAMB}"), Error("field `radius`: not allowed")),
        surface("rectangle: corner inf", "rectangle", &format!("corner = [inf, 0, 1]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\n{LAMB}"), Error("field `corner`")),
        surface("rectangle: 1e-12 m wide", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [1e-12, 0, 0]\nedge2 = [0, 1, 0]\n{LAMB}"), Accept("E_avg")),
        surface("rectangle: edges 1e11 m", "rectangle", &format!("corner = [0, 0, 1]\nedge1 = [1e11, 0, 0]\nedge2 = [0, 1e11, 0]\n{LAMB}"), Error("field `edge1`: every component must lie within +-1e8")),
        surface("rectangle: 2e8 m from the origin", "rectangle", &format!("corner = [2e8, 0, 1]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\n{LAMB}"), Error("field `corner`: every component must lie within +-1e8")),
        // Disc.
        surface("disc: radius 0", "disc", &format!("center = [0, 0, 1]\nnormal = [0, 0, 1]\nradius = 0\n{LAMB}"), Error("field `radius`")),
        surface("disc: radius negative", "disc", &format!("center = [0, 0, 1]\nnormal = [0, 0, 1]\nradius = -1\n{LAMB}"), Error("field `radius`")),
        surface("disc: radius nan", "disc", &format!("center = [0, 0, 1]\nnormal = [0, 0, 1]\nradius = nan\n{LAMB}"), Error("field `radius`")),
        surface("disc: radius 1e300", "disc", &format!("center = [0, 0, 1]\nnormal = [0, 0, 1]\nradius = 1e300\n{LAMB}"), Error("field `radius`")),
        surface("disc: normal zero", "disc", &format!("center = [0, 0, 1]\nnormal = [0, 0, 0]\nradius = 1\n{LAMB}"), Error("field `normal`")),
        surface("disc: sides = \"outside\"", "disc", &format!("center = [0, 0, 1]\nnormal = [0, 0, 1]\nradius = 1\nsides = \"outside\"\n{LAMB}"), Error("field `sides`")),
        // Sphere.
        surface("sphere: radius 0", "sphere", &format!("center = [1, 1, 1]\nradius = 0\n{LAMB}"), Error("field `radius`")),
        surface("sphere: center missing", "sphere", &format!("radius = 0.2\n{LAMB}"), Error("field `center`: missing field")),
        surface("sphere: sides = \"front\"", "sphere", &format!("center = [1, 1, 1]\nradius = 0.2\nsides = \"front\"\n{LAMB}"), Error("field `sides`: must be one of `outside`")),
        surface("sphere: with a normal", "sphere", &format!("center = [1, 1, 1]\nradius = 0.2\nnormal = [0, 0, 1]\n{LAMB}"), Error("field `normal`: not allowed")),
        // Box.
        surface("box: min equals max", "box", &format!("min = [0, 0, 0]\nmax = [0, 0, 0]\n{LAMB}"), Error("field `max`: every component must exceed")),
        surface("box: min above max", "box", &format!("min = [1, 1, 1]\nmax = [0, 2, 2]\n{LAMB}"), Error("field `max`")),
        surface("box: normals = \"sideways\"", "box", &format!("min = [0, 0, 0]\nmax = [1, 1, 1]\nnormals = \"sideways\"\n{LAMB}"), Error("field `normals`: must be one of `inward`, `outward`")),
        surface("box: unknown face `top`", "box", "min = [0, 0, 0]\nmax = [1, 1, 1]\nfaces = { top = { type = \"lambertian\", reflectance = 0.5 } }", Error("unknown field `top`")),
        surface("box: faces without material for the rest", "box", "min = [0, 0, 0]\nmax = [1, 1, 1]\nfaces = { z_max = { type = \"lambertian\", reflectance = 0.5 } }", Error("field `material`: missing field (needed for face `x_min`")),
        surface("box: all six faces given, no material", "box", "min = [0.5, 0.5, 0]\nmax = [1, 1, 0.5]\nnormals = \"outward\"\nfaces = { x_min = { type = \"lambertian\", reflectance = 0.5 }, x_max = { type = \"lambertian\", reflectance = 0.5 }, y_min = { type = \"lambertian\", reflectance = 0.5 }, y_max = { type = \"lambertian\", reflectance = 0.5 }, z_min = { type = \"lambertian\", reflectance = 0.5 }, z_max = { type = \"lambertian\", reflectance = 0.5 } }", Accept("E_avg")),
        surface("box: face reflectance 2", "box", "min = [0, 0, 0]\nmax = [1, 1, 1]\nfaces = { z_max = { type = \"lambertian\", reflectance = 2 } }\nmaterial = { type = \"lambertian\", reflectance = 0.5 }", Error("field `reflectance`")),
        surface("box: with a radius", "box", &format!("min = [0, 0, 0]\nmax = [1, 1, 1]\nradius = 1\n{LAMB}"), Error("field `radius`: not allowed")),
        // Mesh keys.
        surface("mesh: file missing on disk", "mesh", &format!("file = \"nowhere.obj\"\n{LAMB}"), Error("field `file`: ")),
        surface("mesh: file is a folder", "mesh", &format!("file = \".\"\n{LAMB}"), Error("field `file`: ")),
        surface("mesh: no `file`", "mesh", LAMB, Error("field `file`: missing field")),
        surface("mesh: scale 0", "mesh", &format!("file = \"m.obj\"\nscale = 0\n{LAMB}"), Error("field `scale`: must be finite and > 0, got 0")),
        surface("mesh: scale -1", "mesh", &format!("file = \"m.obj\"\nscale = -1\n{LAMB}"), Error("field `scale`")),
        surface("mesh: rotate with nan", "mesh", &format!("file = \"m.obj\"\nrotate = [0, nan, 0]\n{LAMB}"), Error("field `rotate`")),
        surface("mesh: translate 1e13", "mesh", &format!("file = \"m.obj\"\ntranslate = [1e13, 0, 0]\n{LAMB}"), Error("field `translate`")),
        surface("mesh: scale 1e30 (vertices beyond the limit)", "mesh", &format!("file = \"m.obj\"\nscale = 1e30\n{LAMB}"), Error("field `file`")),
        surface("mesh: sides = \"outside\"", "mesh", &format!("file = \"m.obj\"\nsides = \"outside\"\n{LAMB}"), Error("field `sides`")),
        surface("mesh: with a center", "mesh", &format!("file = \"m.obj\"\ncenter = [0, 0, 0]\n{LAMB}"), Error("field `center`: not allowed")),
        // SH keys.
        surface("sh: both file and coefficients", "sh", &format!("file = \"c.csv\"\ncoefficients = [[0, 0, 0.3, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("give either `file` or `coefficients`")),
        surface("sh: neither file nor coefficients", "sh", &format!("center = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`: missing field")),
        surface("sh: k not whole", "sh", &format!("coefficients = [[0.5, 0, 0.3, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`: degree k and order m must be whole numbers")),
        surface("sh: m above k", "sh", &format!("coefficients = [[0, 0, 0.3, 0], [1, 2, 0.1, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`")),
        surface("sh: negative radius everywhere", "sh", &format!("coefficients = [[0, 0, -0.3, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`")),
        surface("sh: radius zero somewhere", "sh", &format!("coefficients = [[0, 0, 0.3, 0], [1, 0, 0.3, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`")),
        surface("sh: coefficient inf", "sh", &format!("coefficients = [[0, 0, inf, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`")),
        surface("sh: degree 101", "sh", &format!("coefficients = [[0, 0, 0.3, 0], [101, 0, 0.001, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `coefficients`")),
        surface("sh: center missing", "sh", &format!("coefficients = [[0, 0, 0.3, 0]]\n{LAMB}"), Error("field `center`: missing field")),
        surface("sh: file missing on disk", "sh", &format!("file = \"none.csv\"\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("field `file`: ")),
        surface("sh: coefficient row of three", "sh", &format!("coefficients = [[0, 0, 0.3]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Error("s.toml:")),
        surface("sh: scale 0", "sh", &format!("coefficients = [[0, 0, 0.3, 0]]\ncenter = [-1, -1, 0.5]\nscale = 0\n{LAMB}"), Error("field `scale`")),
        surface("sh: a sphere of radius 0.3 as k = 0 only", "sh", &format!("coefficients = [[0, 0, 0.3, 0]]\ncenter = [-1, -1, 0.5]\n{LAMB}"), Accept("E_avg")),
        // Sphere lights.
        light("sphere light: radius 0", "sphere", "center = [0.5, 0.5, 2]\nradius = 0\nintensity = 10", Error("field `radius`")),
        light("sphere light cutting the room's ceiling", "sphere", "name = \"globe\"\ncenter = [0.5, 0.5, 2.9]\nradius = 0.2\nintensity = 10", Warn("WARNING: globe: about 25 % of the sphere light's surface lies beyond a surface")),
        light("sphere light: radius missing", "sphere", "center = [0.5, 0.5, 2]\nintensity = 10", Error("field `radius`: missing field")),
        light("sphere light: with a position", "sphere", "position = [0.5, 0.5, 2]\nradius = 0.1\nintensity = 10", Error("s.toml:")),
        light("sphere light: with a direction", "sphere", "center = [0.5, 0.5, 2]\nradius = 0.1\nintensity = 10\ndirection = [0, 0, -1]", Error("field `direction`: not allowed")),
        light("sphere light: cuts the floor of the room", "sphere", "center = [0.5, 0.5, 0.05]\nradius = 0.1\nintensity = 10", Accept("E_avg")),
        // Spots.
        light("spot: inner above outer", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 40\nouter = 20\nintensity = 10", Error("field `outer`: must be > 0 and >= `inner` (40 degrees), got 20")),
        light("spot: outer 200 degrees", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 20\nouter = 200\nintensity = 10", Error("field `outer`: must lie in [0, 180] degrees, got 200")),
        light("spot: inner negative", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = -5\nouter = 20\nintensity = 10", Error("field `inner`")),
        light("spot: direction zero", "spot", "position = [0, 0, 2]\ndirection = [0, 0, 0]\ninner = 10\nouter = 20\nintensity = 10", Error("field `direction`")),
        light("spot: direction missing", "spot", "position = [0, 0, 2]\ninner = 10\nouter = 20\nintensity = 10", Error("field `direction`: missing field")),
        light("spot: outer 0 with a flux", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 0\nouter = 0\nflux = 100", Error("field `outer`")),
        light("spot: outer 1e-6 degrees with a flux", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 0\nouter = 1e-6\nflux = 100", Error("field `outer`: must be at least 0.01 degrees")),
        light("spot: outer 0.01 degrees with a flux", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 0\nouter = 0.01\nflux = 100", Accept("E_avg")),
        light("spot: outer 0 with an intensity", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 0\nouter = 0\nintensity = 100", Error("field `outer`: must be > 0")),
        light("spot: 180/180 is a point light", "spot", "position = [0, 0, 2.5]\ndirection = [0, 0, -1]\ninner = 180\nouter = 180\nintensity = 100", Accept("E_avg 88.3417")),
        light("spot: pointing at the ceiling it sits on", "spot", "position = [0, 0, 3]\ndirection = [0, 0, 1]\ninner = 10\nouter = 20\nintensity = 100", Accept("E_avg 44.8288")),
        light("spot: with a radius", "spot", "position = [0, 0, 2]\ndirection = [0, 0, -1]\ninner = 10\nouter = 20\nintensity = 10\nradius = 1", Error("field `radius`")),
        // Photometric lights.
        light("ies: file missing on disk", "ies", "file = \"none.ies\"\nposition = [0, 0, 2.5]", Error("field `file`: ")),
        light("ies: no `file`", "ies", "position = [0, 0, 2.5]", Error("field `file`: missing field")),
        light("ies: file is not IES (an OBJ)", "ies", "file = \"m.obj\"\nposition = [0, 0, 2.5]", Error("field `file`")),
        light("ies: an .ldt file given as type ies", "ies", "file = \"f.ldt\"\nposition = [0, 0, 2.5]", Error("field `file`")),
        light("ies: aim zero", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\naim = [0, 0, 0]", Error("field `aim`")),
        light("ies: multiplier negative", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nmultiplier = -1", Error("field `multiplier`")),
        light("ies: flux and multiplier", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nmultiplier = 2\nflux = 100", Error("s.toml:")),
        light("ies: rotate nan", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nrotate = nan", Error("field `rotate`")),
        light("ies: rotate 1e300", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nrotate = 1e300", Accept("E_avg")),
        light("ies: opening = \"yes\"", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nopening = \"yes\"", Error("s.toml:")),
        light("ies: opening = true with no opening in the file", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nopening = true", Error("field `opening`")),
        light("ies: with an intensity", "ies", "file = \"f.ies\"\nposition = [0, 0, 2.5]\nintensity = 5", Error("field `intensity`")),
        light("ies: plain file on the ceiling", "ies", "file = \"f.ies\"\nposition = [0, 0, 3]", Accept("E_avg")),
        light("ldt: plain file", "ldt", "file = \"f.ldt\"\nposition = [0, 0, 2.9]", Accept("E_avg")),
        light("ldt: an .ies file given as type ldt", "ldt", "file = \"f.ies\"\nposition = [0, 0, 2.5]", Error("field `file`")),
        // Area lights.
        light("rectangle light: luminance negative", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = -1", Error("field `luminance`")),
        light("rectangle light: luminance and flux", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = 100\nflux = 100", Error("s.toml:")),
        light("rectangle light: parallel edges", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [1, 0, 0]\nluminance = 100", Error("s.toml:")),
        light("rectangle light: sides = \"back\"", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = 100\nsides = \"back\"", Error("field `sides`")),
        light("rectangle light: material reflectance 3", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = 100\nmaterial = { type = \"lambertian\", reflectance = 3 }", Error("field `reflectance`")),
        light("rectangle light: with a profile", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = 100\nprofile = \"uniform\"", Error("field `profile`")),
        light("rectangle light: in the ceiling plane", "rectangle", "corner = [0, 0, 3]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = 100", Accept("E_avg")),
        light("rectangle light: facing the ceiling it lies in", "rectangle", "corner = [0, 0, 3]\nedge1 = [0.5, 0, 0]\nedge2 = [0, 0.5, 0]\nluminance = 100", Accept("E_avg 42.3959")),
        light("rectangle light: luminance 1e70", "rectangle", "corner = [0, 0, 2.9]\nedge1 = [0.5, 0, 0]\nedge2 = [0, -0.5, 0]\nluminance = 1e70", Error("field `luminance`")),
        light("disc light: radius 0", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0\nluminance = 100", Error("field `radius`")),
        light("disc light: normal missing", "disc", "center = [0, 0, 2.9]\nradius = 0.2\nluminance = 100", Error("field `normal`: missing field")),
        light("disc light: profile unknown", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = \"gaussian\"", Error("field `profile`")),
        light("disc light: tent turning beyond the radius", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = { type = \"tent\", turning = 0.5 }", Error("field `profile`")),
        light("disc light: v turning negative", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = { type = \"v\", turning = -0.1 }", Error("field `profile`")),
        light("disc light: table not ascending", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = { type = \"tabulated\", s = [0, 0.1, 0.05, 0.2], l = [1, 1, 1, 1] }", Error("field `profile`")),
        light("disc light: table lengths differ", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = { type = \"tabulated\", s = [0, 0.2], l = [1, 1, 1] }", Error("field `profile`")),
        light("disc light: table with a negative luminance", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = { type = \"tabulated\", s = [0, 0.2], l = [1, -1] }", Error("field `profile`")),
        light("disc light: profile as a number", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\nprofile = 3", Error("field `profile`")),
        light("disc light: with inner", "disc", "center = [0, 0, 2.9]\nnormal = [0, 0, -1]\nradius = 0.2\nluminance = 100\ninner = 3", Error("field `inner`")),
        // Lights inside solids and behind surfaces.
        scene_add("point light inside a solid box", &format!("[[surface]]\ntype = \"box\"\nmin = [-0.5, -0.5, 2]\nmax = [0.5, 0.5, 2.8]\nnormals = \"outward\"\n{LAMB}\n"), Warn("WARNING: lamp is sealed inside a solid")),
        scene_add("point light inside a solid sphere", &format!("[[surface]]\ntype = \"sphere\"\ncenter = [0, 0, 2.5]\nradius = 0.2\n{LAMB}\n"), Warn("WARNING: lamp is sealed inside a solid")),
        scene_add("point light on a desk top", &format!("[[surface]]\ntype = \"box\"\nmin = [-0.5, -0.5, 0]\nmax = [0.5, 0.5, 2.5]\nnormals = \"outward\"\n{LAMB}\n"), Accept("E_avg")),
        scene_add("point light under a one-sided panel facing up", &format!("[[surface]]\ntype = \"rectangle\"\ncorner = [-1.9, -1.9, 2.6]\nedge1 = [3.8, 0, 0]\nedge2 = [0, 3.8, 0]\n{LAMB}\n"), Accept("E_avg")),
    ];
    c.push(case(
        Ch::Scene,
        "huge scene file (20,000 point lights)",
        text(format!(
            "{SCENE}{}",
            (0..20_000)
                .map(|k| format!(
                    "[[light]]\ntype = \"point\"\nposition = [{}, 0, 2]\nintensity = 0.001\n",
                    -1.9 + (k as f64) * 1.9e-4
                ))
                .collect::<String>()
        )),
        Accept("E_avg"),
    ));
    c
}

fn points_cases() -> Vec<Case> {
    let mut c = vec![
        points("empty file", "", Error("p.csv")),
        points("header only", "x,y,z,nx,ny,nz\n", Error("p.csv")),
        points(
            "hemispherical receiver on the floor",
            "x,y,z,nx,ny,nz,receiver\n0,0,0,0,0,1,hemispherical\n",
            Error(
                "p.csv:2: a hemispherical receiver lies on a surface, so part of it would be inside: place it off the surface (a small `offset`",
            ),
        ),
        points(
            "cylindrical receiver on the floor",
            "x,y,z,nx,ny,nz,receiver\n0,0,0,0,0,1,cylindrical\n",
            Error(
                "p.csv:2: a cylindrical receiver lies on a surface, so part of it would be inside: place it off the surface (EN 12464-1 asks",
            ),
        ),
        points(
            "column `nz` missing",
            "x,y,z,nx,ny\n0,0,0.75,0,0\n",
            Error("missing column `nz`"),
        ),
        points(
            "header in capitals",
            "X,Y,Z,NX,NY,NZ\n0,0,0.75,0,0,1\n",
            Error("missing column `x`"),
        ),
        points("no header", "0,0,0.75,0,0,1\n", Error("missing column")),
        points(
            "x not a number",
            "id,x,y,z,nx,ny,nz\na,abc,0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "x empty",
            "id,x,y,z,nx,ny,nz\na,,0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "decimal comma (quoted)",
            "id,x,y,z,nx,ny,nz\na,\"0,5\",0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "decimal comma (unquoted: too many cells)",
            "id,x,y,z,nx,ny,nz\na,0,5,0,0.75,0,0,1\n",
            Error("p.csv:2"),
        ),
        points(
            "semicolons",
            "id;x;y;z;nx;ny;nz\na;0;0;0.75;0;0;1\n",
            Error("seems to use `;`"),
        ),
        points(
            "tabs",
            "id\tx\ty\tz\tnx\tny\tnz\na\t0\t0\t0.75\t0\t0\t1\n",
            Error("seems to use tabs"),
        ),
        // An unclosed quote runs to the end of the file: said.
        points(
            "unclosed quote",
            "id,x,y,z,nx,ny,nz\n\"a,0,0,0.75,0,0,1\nb,1,0,0.75,0,0,1\n",
            Error(
                "p.csv:2: 1 cells where the header has 7 columns (a cell runs over several lines: an unclosed `\"` quote?)",
            ),
        ),
        points("byte-order mark", &format!("\u{feff}{POINTS}"), Same),
        // The mark hid the comment's `#`: the comment became the header.
        points(
            "byte-order mark before a comment",
            &format!("\u{feff}# office grid\n{POINTS}"),
            Same,
        ),
        points(
            "byte-order mark before `x`",
            "\u{feff}x,y,z,nx,ny,nz,id\n0,0,0.75,0,0,1,a\n1,1,0.75,0,0,1,b\n-1,0.5,0.75,0,0,1,c\n",
            Accept("E_avg 44.1439"),
        ),
        points("CRLF line ends", &POINTS.replace('\n', "\r\n"), Same),
        points("no newline at the end", POINTS.trim_end(), Same),
        points(
            "blank lines between rows",
            &POINTS.replace('\n', "\n\n"),
            Same,
        ),
        // Blank lines of spaces and tabs too (they were 1 cell of 7).
        points(
            "lines of spaces between rows",
            &POINTS.replace('\n', "\n  \t \n"),
            Same,
        ),
        points(
            "comment lines before the header",
            &format!("# office grid\n# z = 0.75\n{POINTS}"),
            Same,
        ),
        points(
            "columns in another order",
            "nz,ny,nx,z,y,x,id\n1,0,0,0.75,0,0,a\n1,0,0,0.75,1,1,b\n1,0,0,0.75,0.5,-1,c\n",
            Same,
        ),
        points(
            "extra columns",
            "id,room,x,y,z,nx,ny,nz,note\na,1,0,0,0.75,0,0,1,x\nb,1,1,1,0.75,0,0,1,y\nc,2,-1,0.5,0.75,0,0,1,z\n",
            Same,
        ),
        points(
            "quoted numbers",
            "id,x,y,z,nx,ny,nz\n\"a\",\"0\",\"0\",\"0.75\",\"0\",\"0\",\"1\"\nb,1,1,0.75,0,0,1\nc,-1,0.5,0.75,0,0,1\n",
            Same,
        ),
        points(
            "spaces around numbers",
            "id,x,y,z,nx,ny,nz\na, 0, 0, 0.75, 0, 0, 1\nb,1,1,0.75,0,0,1\nc,-1,0.5,0.75,0,0,1\n",
            Same,
        ),
        points(
            "normal not of unit length",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,5\nb,1,1,0.75,0,0,0.2\nc,-1,0.5,0.75,0,0,1\n",
            Same,
        ),
        points(
            "leading plus signs and exponents",
            "id,x,y,z,nx,ny,nz\na,+0,0e0,75e-2,0,0,+1\nb,1,1,0.75,0,0,1\nc,-1,0.5,0.75,0,0,1\n",
            Same,
        ),
        points(
            "duplicate ids",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1\na,1,1,0.75,0,0,1\na,-1,0.5,0.75,0,0,1\n",
            Accept("3 rows read"),
        ),
        points(
            "ids starting with #",
            "id,x,y,z,nx,ny,nz\n#1,0,0,0.75,0,0,1\n#2,1,1,0.75,0,0,1\n",
            Accept("2 rows read"),
        ),
        points(
            "duplicate column `x`",
            "x,y,z,nx,ny,nz,x\n0,0,0.75,0,0,1,0\n",
            Error("p.csv:1: field `x`"),
        ),
        points(
            "result column `E` in the input",
            "x,y,z,nx,ny,nz,E\n0,0,0.75,0,0,1,5\n",
            Error("`E`"),
        ),
        points(
            "short row",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0\n",
            Error("p.csv:2"),
        ),
        points(
            "long row",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1,9\n",
            Error("p.csv:2"),
        ),
        points(
            "x nan",
            "id,x,y,z,nx,ny,nz\na,nan,0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "x NaN",
            "id,x,y,z,nx,ny,nz\na,NaN,0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "y inf",
            "id,x,y,z,nx,ny,nz\na,0,inf,0.75,0,0,1\n",
            Error("p.csv:2: field `y`"),
        ),
        points(
            "z 1e400 (overflows)",
            "id,x,y,z,nx,ny,nz\na,0,0,1e400,0,0,1\n",
            Error("p.csv:2: field `z`"),
        ),
        points(
            "x 1e300 (shown short)",
            "id,x,y,z,nx,ny,nz\na,1e300,0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "x 1e13 m",
            "id,x,y,z,nx,ny,nz\na,1e13,0,0.75,0,0,1\n",
            Error("p.csv:2: field `x`"),
        ),
        points(
            "normal zero",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,0\n",
            Error("p.csv:2"),
        ),
        // Any non-zero length is a direction, whose square may leave the
        // range of f64 (1e200 read "zero length", 1e-160 "not finite").
        // Two cells of 1e308 m^2 made the grid's area inf and E_avg NaN.
        points(
            "area 1e308",
            "id,grid,x,y,z,nx,ny,nz,area\na,g,0,0,0.75,0,0,1,1e308\n",
            Error("p.csv:2: field `area`: an area weight must be positive and at most"),
        ),
        // A grid's figures average one quantity (a mixed grid's E_avg
        // mixed E_h and E_z, with verdicts).
        points(
            "grid mixing receiver types",
            "id,grid,x,y,z,nx,ny,nz,receiver\na,g,0,0,0.75,0,0,1,planar\nb,g,1,0,0.75,0,0,1,cylindrical\n",
            Error(
                "p.csv:3: field `receiver`: grid `g` mixes receiver types (`cylindrical` here, `planar` on line 2)",
            ),
        ),
        points(
            "normal 1e200",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1e200\n",
            Accept("E_avg"),
        ),
        points(
            "normal 1e-160",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1e-160\n",
            Accept("E_avg"),
        ),
        points(
            "normal 1e-320 (denormal)",
            "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1e-320\n",
            Accept("E_avg"),
        ),
        points(
            "error on line 5 after a comment and a blank line",
            "# c\nid,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1\n\nb,1,x,0.75,0,0,1\n",
            Error("p.csv:5: field `y`"),
        ),
        points(
            "point on the light",
            "id,x,y,z,nx,ny,nz\na,0,0,2.5,0,0,1\n",
            Error("p.csv:2: point lies on or inside lamp at (0, 0, 2.5) m"),
        ),
        points(
            "point 1e-9 m below the light",
            "id,x,y,z,nx,ny,nz\na,0,0,2.499999999,0,0,1\n",
            Accept("E_avg 1.0000e20 lx"),
        ),
        points(
            "point on the floor",
            "id,x,y,z,nx,ny,nz\na,0,0,0,0,0,1\n",
            Accept("E_avg"),
        ),
        points(
            "point below the floor",
            "id,x,y,z,nx,ny,nz\na,0,0,-0.5,0,0,1\n",
            Flag("enclosed"),
        ),
        points(
            "point outside the room",
            "id,x,y,z,nx,ny,nz\na,5,0,1,-1,0,0\n",
            Accept("E_avg 0.0000"),
        ),
        points(
            "point facing the wall it is on",
            "id,x,y,z,nx,ny,nz\na,2,0,1,1,0,0\n",
            Flag("enclosed"),
        ),
        points(
            "point in a corner",
            "id,x,y,z,nx,ny,nz\na,2,2,3,-1,-1,-1\n",
            Accept("E_avg"),
        ),
        points(
            "invalid UTF-8",
            "",
            Error("p.csv:2: the byte at column 1 is not UTF-8 text"),
        ),
        points("a folder", "", Error("p.csv")),
        points("file missing", "", Error("p.csv")),
        points(
            "views file given as points",
            VIEWS,
            Error("missing column `nx`"),
        ),
    ];
    let n = c.len();
    c[n - 4].body = Body::Bytes(b"id,x,y,z,nx,ny,nz\n\xe4,0,0,0.75,0,0,1\n".to_vec());
    c[n - 3].body = Body::Folder;
    c[n - 2].body = Body::Missing;
    let big: String = std::iter::once("id,x,y,z,nx,ny,nz\n".to_string())
        .chain((0..20_000).map(|k| {
            format!(
                "p{k},{},{},0.75,0,0,1\n",
                -1.9 + (k % 100) as f64 * 0.038,
                -1.9 + (k / 100) as f64 * 0.019
            )
        }))
        .collect();
    c.push(points("20,000 points", &big, Accept("20000 rows read")));
    let mut bad_deep = big.clone();
    bad_deep.push_str("last,0,0,zz,0,0,1\n");
    c.push(points(
        "a bad cell 20,002 lines down",
        &bad_deep,
        Error("p.csv:20002: field `z`"),
    ));
    c.push(Case {
        stdin: Some(POINTS.to_string()),
        ..cli("points from standard input", "illuminance --scene {s} --points - --out - --chains 1024 --batch-size 32 --threads 1 --quiet", Accept("a,0,0,0.75,0,0,1,5"))
    });
    c
}

fn views_cases() -> Vec<Case> {
    let mut c = vec![
        views("empty file", "", Error("v.csv")),
        views(
            "column `dz` missing",
            "x,y,z,dx,dy\n0,0,1.5,0,0\n",
            Error("missing column `dz`"),
        ),
        views(
            "direction zero",
            "x,y,z,dx,dy,dz\n0,0,1.5,0,0,0\n",
            Error("v.csv:2"),
        ),
        views(
            "direction nan",
            "x,y,z,dx,dy,dz\n0,0,1.5,0,nan,-1\n",
            Error("v.csv:2: field `dy`"),
        ),
        views(
            "observer 1e300",
            "x,y,z,dx,dy,dz\n1e300,0,1.5,0,0,-1\n",
            Error("v.csv:2: field `x`"),
        ),
        views(
            "not a number",
            "x,y,z,dx,dy,dz\n0,0,one,0,0,-1\n",
            Error("v.csv:2: field `z`"),
        ),
        views("CRLF line ends", &VIEWS.replace('\n', "\r\n"), Same),
        views("byte-order mark", &format!("\u{feff}{VIEWS}"), Same),
        views(
            "direction not of unit length",
            "id,x,y,z,dx,dy,dz\na,0,0,1.5,0,0,-7\nb,1,1,1.5,0.1,0,0\n",
            Same,
        ),
        views(
            "duplicate column",
            "x,y,z,dx,dy,dz,dz\n0,0,1.5,0,0,-1,1\n",
            Error("v.csv:1: field `dz`"),
        ),
        views(
            "result column `L` in the input",
            "x,y,z,dx,dy,dz,L\n0,0,1.5,0,0,-1,3\n",
            Error("`L`"),
        ),
        views(
            "points file given as views",
            POINTS,
            Error("missing column `dx`"),
        ),
        views(
            "observer outside the room looking away",
            "x,y,z,dx,dy,dz\n5,0,1,1,0,0\n",
            Accept("1 rows read"),
        ),
        views(
            "observer outside the room looking at its back",
            "x,y,z,dx,dy,dz\n5,0,1,-1,0,0\n",
            Accept("1 rows read"),
        ),
        views(
            "observer on the light",
            "x,y,z,dx,dy,dz\n0,0,2.5,0,0,-1\n",
            Accept("1 rows read"),
        ),
        views(
            "observer on the floor looking down into it",
            "x,y,z,dx,dy,dz\n0,0,0,0,0,-1\n",
            Accept("1 rows read"),
        ),
        views(
            "semicolons",
            "x;y;z;dx;dy;dz\n0;0;1.5;0;0;-1\n",
            Error("seems to use `;`"),
        ),
        views("file missing", "", Error("v.csv")),
    ];
    let n = c.len();
    c[n - 1].body = Body::Missing;
    c
}

fn obj_cases() -> Vec<Case> {
    vec![
        obj("empty file", "", Error("m.obj")),
        obj(
            "vertices only",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
            Error("m.obj"),
        ),
        obj(
            "vertex with nan",
            &OBJ.replace("v 1.3 1 0.1", "v nan 1 0.1"),
            Error("m.obj"),
        ),
        obj(
            "vertex with two coordinates",
            &OBJ.replace("v 1.3 1 0.1", "v 1.3 1"),
            Error("m.obj"),
        ),
        obj(
            "vertex not a number",
            &OBJ.replace("v 1.3 1 0.1", "v 1.3 one 0.1"),
            Error("m.obj"),
        ),
        obj(
            "vertex 1e300",
            &OBJ.replace("v 1.3 1 0.1", "v 1e300 1 0.1"),
            Error("m.obj"),
        ),
        obj(
            "face index beyond the vertices",
            &OBJ.replace("f 2 3 4", "f 2 3 9"),
            Error("m.obj"),
        ),
        obj(
            "face index 0",
            &OBJ.replace("f 2 3 4", "f 0 3 4"),
            Error("m.obj"),
        ),
        obj(
            "face with two vertices (no area: dropped like a line)",
            &OBJ.replace("f 2 3 4", "f 2 3"),
            Accept("E_avg"),
        ),
        obj(
            "negative (relative) face indices",
            &OBJ.replace("f 2 3 4", "f -3 -2 -1"),
            Same,
        ),
        obj(
            "quads and a pentagon",
            "v 1 1 0.1\nv 1.3 1 0.1\nv 1.3 1.3 0.1\nv 1 1.3 0.1\nv 1.15 1.15 0.4\nf 1 2 3 4\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n",
            Accept("E_avg"),
        ),
        obj("CRLF line ends", &OBJ.replace('\n', "\r\n"), Same),
        obj(
            "normals and texture coordinates",
            "v 1 1 0.1\nv 1.3 1 0.1\nv 1 1.3 0.1\nv 1 1 0.4\nvt 0 0\nvn 0 0 1\nf 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\nf 2 3 4\nf 1 4 3\n",
            Same,
        ),
        obj(
            "a material library that does not exist",
            &format!("mtllib none.mtl\nusemtl red\n{OBJ}"),
            Same,
        ),
        obj(
            "an unknown statement",
            &format!("frobnicate 1 2 3\n{OBJ}"),
            Same,
        ),
        obj(
            "degenerate (collinear) triangle",
            &format!("{OBJ}v 0 0 0.5\nv 0.1 0 0.5\nv 0.2 0 0.5\nf 5 6 7\n"),
            Accept("E_avg"),
        ),
        obj(
            "binary garbage",
            "\u{1}\u{2}\u{3}\u{0}v\u{0}",
            Error("m.obj"),
        ),
        obj(
            "a mesh that crosses the floor",
            &OBJ.replace("v 1 1 0.1", "v 1 1 -0.1"),
            Accept("E_avg"),
        ),
        obj(
            "an open mesh (one triangle)",
            "v 1 1 0.1\nv 1.3 1 0.1\nv 1 1.3 0.1\nf 1 2 3\n",
            Accept("E_avg"),
        ),
        case(Ch::Obj, "file missing", Body::Missing, Error("m.obj")),
        case(Ch::Obj, "a folder", Body::Folder, Error("m.obj")),
    ]
}

fn sh_cases() -> Vec<Case> {
    vec![
        sh("empty file", "", Error("c.csv")),
        sh("header only", "k,m,a,b\n", Error("c.csv")),
        sh(
            "column `b` missing",
            "k,m,a\n0,0,0.3\n",
            Error("missing column `b`"),
        ),
        sh(
            "k not whole",
            "k,m,a,b\n0.5,0,0.3,0\n",
            Error("c.csv:2: field `k`"),
        ),
        sh(
            "m above k",
            "k,m,a,b\n0,0,0.3,0\n1,2,0.1,0\n",
            Error("c.csv:3: field `m`"),
        ),
        sh(
            "a not a number",
            "k,m,a,b\n0,0,abc,0\n",
            Error("c.csv:2: field `a`"),
        ),
        sh(
            "b inf",
            "k,m,a,b\n0,0,0.3,inf\n",
            Error("c.csv:2: field `b`"),
        ),
        sh(
            "degree 101",
            "k,m,a,b\n0,0,0.3,0\n101,0,0.001,0\n",
            Error("c.csv:3: field `k`"),
        ),
        sh("negative radius", "k,m,a,b\n0,0,-0.3,0\n", Error("c.csv")),
        sh(
            "same (k, m) twice",
            "k,m,a,b\n0,0,0.3,0\n0,0,0.1,0\n",
            Error("c.csv"),
        ),
        sh(
            "decimal comma",
            "k,m,a,b\n0,0,\"0,3\",0\n",
            Error("c.csv:2: field `a`"),
        ),
        sh("semicolons", "k;m;a;b\n0;0;0.3;0\n", Error("c.csv")),
        sh("CRLF line ends", &COEFFS.replace('\n', "\r\n"), Same),
        sh(
            "comment before the header",
            &format!("# fitted\n{COEFFS}"),
            Same,
        ),
        sh(
            "columns in another order",
            "b,a,m,k\n0,0.3,0,0\n0,0.05,0,1\n",
            Same,
        ),
        sh(
            "a 1e300 coefficient",
            "k,m,a,b\n0,0,0.3,0\n1,1,1e300,0\n",
            Error("c.csv"),
        ),
        case(Ch::Sh, "file missing", Body::Missing, Error("c.csv")),
    ]
}

fn ies_cases() -> Vec<Case> {
    vec![
        ies("plain file", IES, Accept("flux of the table 444.9 lm")),
        ies("empty file", "", Error("f.ies")),
        ies(
            "no TILT line",
            &IES.replace("TILT=NONE\n", ""),
            Error("f.ies"),
        ),
        ies_line(
            "TILT=INCLUDE without its table",
            3,
            "TILT=INCLUDE",
            Error("f.ies"),
        ),
        ies_line("TILT= a missing file", 3, "TILT=lamp.tlt", Error("f.ies")),
        ies_line("negative candela", 8, "100 -80 50", Error("f.ies:8")),
        ies_line("candela nan", 8, "100 nan 50", Error("f.ies:8")),
        ies_line(
            "candela 1e300 (shown short; above a scene's limit)",
            8,
            "100 1e300 50",
            Error("largest is 1e300 cd"),
        ),
        // Finite numbers whose product overflows: no NaN, no infinity, and
        // `--plot` does not stall on an infinite axis.
        ies_line(
            "candela 1.7e308",
            8,
            "100 1.7e308 50",
            Error("intensities out of range"),
        ),
        ies_line(
            "candela multiplier 1e308",
            4,
            "1 1000 1e308 3 1 1 2 0 0 0",
            Error("intensities out of range"),
        ),
        ies_line(
            "lamp lumens 1e-308",
            4,
            "1 1e-308 1 3 1 1 2 0 0 0",
            Accept("light output ratio out of range"),
        ),
        ies_line("candela not a number", 8, "100 eighty 50", Error("f.ies:8")),
        ies_line(
            "vertical angles not ascending",
            6,
            "0 90 45",
            Error("f.ies:6"),
        ),
        ies_line("vertical angle 200", 6, "0 45 200", Error("f.ies:6")),
        ies_line("horizontal angle 400", 7, "400", Error("f.ies:7")),
        ies_line("too few candela values", 8, "100 80", Error("f.ies")),
        ies_line(
            "too many candela values",
            8,
            "100 80 50 20",
            Error("f.ies:8: end of file: unexpected `20`"),
        ),
        ies_line(
            "photometric type 4",
            4,
            "1 1000 1 3 1 4 2 0 0 0",
            Error("f.ies:4"),
        ),
        ies_line(
            "units type 3",
            4,
            "1 1000 1 3 1 1 3 0 0 0",
            Error("f.ies:4"),
        ),
        ies_line(
            "zero vertical angles",
            4,
            "1 1000 1 0 1 1 2 0 0 0",
            Error("f.ies:4"),
        ),
        ies_line(
            "number of vertical angles 1e9",
            4,
            "1 1000 1 1000000000 1 1 2 0 0 0",
            Error("f.ies"),
        ),
        ies_line(
            "multiplier 0",
            4,
            "1 1000 0 3 1 1 2 0 0 0",
            Error("f.ies:4: candela multiplier: must be > 0, got 0"),
        ),
        ies_line(
            "multiplier negative",
            4,
            "1 1000 -1 3 1 1 2 0 0 0",
            Error("f.ies:4"),
        ),
        ies_line(
            "lumens -1 (absolute photometry)",
            4,
            "1 -1 1 3 1 1 2 0 0 0",
            Accept("flux of the table 444.9 lm"),
        ),
        ies_line(
            "opening width negative",
            4,
            "1 1000 1 3 1 1 2 -0.3 0 0",
            Accept("flux of the table"),
        ),
        ies(
            "CRLF line ends",
            &IES.replace('\n', "\r\n"),
            Accept("flux of the table 444.9 lm"),
        ),
        ies(
            "CR line ends (old Mac OS)",
            &IES.replace('\n', "\r"),
            Accept("flux of the table 444.9 lm"),
        ),
        ies(
            "DOS end-of-file mark (Ctrl-Z) after the data",
            &format!("{IES}\u{1a}"),
            Accept("flux of the table 444.9 lm"),
        ),
        ies(
            "Latin-1 byte in a keyword",
            "IESNA:LM-63-2002\n[TEST] Leuchte f\u{fc}r B\u{fc}ro\nTILT=NONE\n1 1000 1 3 1 1 2 0 0 0\n1.0 1.0 20\n0 45 90\n0\n100 80 50\n",
            Accept("flux of the table 444.9 lm"),
        ),
        ies(
            "values spread over many lines",
            "IESNA:LM-63-2002\nTILT=NONE\n1\n1000\n1\n3\n1\n1\n2\n0\n0\n0\n1.0\n1.0\n20\n0\n45\n90\n0\n100\n80\n50\n",
            Accept("flux of the table 444.9 lm"),
        ),
        ies("an EULUMDAT file named .ies", &ldt(), Error("f.ies")),
        case(Ch::Ies, "file missing", Body::Missing, Error("f.ies")),
        case(Ch::Ies, "a folder", Body::Folder, Error("f.ies")),
    ]
}

fn ldt_cases() -> Vec<Case> {
    vec![
        case(
            Ch::Ldt,
            "plain file",
            text(ldt()),
            Accept("flux of the table"),
        ),
        case(Ch::Ldt, "empty file", text(""), Error("f.ldt")),
        case(
            Ch::Ldt,
            "truncated after 30 lines",
            text(ldt().lines().take(30).collect::<Vec<_>>().join("\n")),
            Error("f.ldt"),
        ),
        ldt_line("Isym 7", 3, "7", Error("f.ldt:3")),
        ldt_line(
            "conversion factor 1e308",
            24,
            "1e308",
            Error("intensities out of range"),
        ),
        ldt_line("Ityp 9", 2, "9", Error("f.ldt:2")),
        ldt_line("Mc 0", 4, "0", Error("f.ldt:4")),
        ldt_line("Ng 0", 6, "0", Error("f.ldt:6")),
        ldt_line("Ng not a number", 6, "nineteen", Error("f.ldt:6")),
        ldt_line("Ng 1e9", 6, "1000000000", Error("f.ldt")),
        ldt_line("luminaire length negative", 13, "-300", Error("f.ldt:13")),
        ldt_line("number of lamp sets 0", 26, "0", Error("f.ldt")),
        ldt_line(
            "total lamp flux with a decimal comma",
            29,
            "1000,0",
            Accept("flux of the table"),
        ),
        ldt_line("an intensity negative", 90, "-5.0", Error("f.ldt:90")),
        ldt_line("an intensity nan", 90, "nan", Error("f.ldt:90")),
        ldt_line(
            "an intensity 1e300 (shown short; above a scene's limit)",
            90,
            "1e300",
            Error("largest is 1e300 cd"),
        ),
        ldt_line(
            "a gamma angle 1e300 (shown short)",
            70,
            "1e300",
            Error("f.ldt:67: gamma angles: angle 4 = 1e300 lies outside [0, 180] degrees"),
        ),
        ldt_line(
            "a gamma angle out of order",
            70,
            "2.0",
            Error("f.ldt:67: gamma angles: angles must ascend"),
        ),
        ldt_line(
            "a C angle out of order",
            50,
            "400.0",
            Error("f.ldt:43: C angles"),
        ),
        ldt_line(
            "conversion factor 0",
            24,
            "0",
            Error("f.ldt:24: conversion factor for luminous intensities: must be > 0, got 0"),
        ),
        case(
            Ch::Ldt,
            "CRLF line ends",
            text(ldt().replace('\n', "\r\n")),
            Accept("flux of the table"),
        ),
        case(
            Ch::Ldt,
            "DOS end-of-file mark (Ctrl-Z) after the data",
            text(format!("{}\u{1a}", ldt())),
            Accept("flux of the table"),
        ),
        case(Ch::Ldt, "an IES file named .ldt", text(IES), Error("f.ldt")),
        case(Ch::Ldt, "file missing", Body::Missing, Error("f.ldt")),
    ]
}

fn cli_cases() -> Vec<Case> {
    let run = "--chains 1024 --batch-size 32 --threads 1";
    vec![
        ill(
            "--chains 0",
            "--chains 0",
            Error("--chains must be positive"),
        ),
        ill("--chains -5", "--chains -5", Error("--chains")),
        ill(
            "--chains abc",
            "--chains abc",
            Error("`abc` is not a whole number of chains"),
        ),
        ill(
            "--chains 1.5",
            "--chains 1.5",
            Error("`1.5` is not a whole number"),
        ),
        ill(
            "--chains 1e30",
            "--chains 1e30",
            Error("`1e30` is not a whole number"),
        ),
        ill(
            "--chains 1e3 (scientific)",
            "--chains 1e3 --batch-size 32 --threads 1",
            Accept("1024 chains"),
        ),
        ill(
            "--time 0",
            "--time 0",
            Error("--time must be a positive number of seconds, got 0"),
        ),
        ill(
            "--time -1",
            "--time -1",
            Error("--time must be a positive number of seconds, got -1"),
        ),
        ill(
            "--time nan",
            "--time nan",
            Error("--time must be a positive number"),
        ),
        ill(
            "--time inf",
            "--time inf",
            Error("--time must be a positive number"),
        ),
        ill(
            "--time -1e300 (shown short)",
            "--time -1e300",
            Error("got -1e300"),
        ),
        ill("--time abc", "--time abc", Error("--time")),
        ill(
            "--rel-error 0",
            "--rel-error 0",
            Error("--rel-error must be positive"),
        ),
        ill("--rel-error -1", "--rel-error -1", Error("--rel-error")),
        ill(
            "--rel-error 1e-300 with --time",
            "--rel-error 1e-300 --time 0.3 --threads 1",
            Accept("target MISSED"),
        ),
        ill("--seed -1", "--seed -1", Error("--seed")),
        ill(
            "--seed 18446744073709551615",
            &format!("--seed 18446744073709551615 {run}"),
            Accept("E_avg"),
        ),
        ill("--threads -1", "--threads -1", Error("--threads")),
        ill(
            "--threads 64 (more than the cores)",
            "--chains 1024 --batch-size 32 --threads 64",
            Accept("E_avg 44.1439"),
        ),
        ill(
            "--orders 101",
            "--orders 101",
            Error("--orders must be at most 100"),
        ),
        ill(
            "--orders 4294967295",
            "--orders 4294967295",
            Error("--orders must be at most 100"),
        ),
        ill(
            "--orders 4294967296",
            "--orders 4294967296",
            Error("--orders"),
        ),
        ill(
            "--orders 3",
            &format!("--orders 3 {run}"),
            Accept("E_avg 44.1439"),
        ),
        ill(
            "--max-order 0",
            "--max-order 0",
            Error("--max-order must be at least 1"),
        ),
        ill(
            "--max-order 1: direct and one reflection",
            &format!("--max-order 1 {run}"),
            Accept("E_avg"),
        ),
        ill(
            "--batch-size 0",
            "--batch-size 0",
            Error("--batch-size must lie in [1, 2^32]"),
        ),
        ill(
            "--batch-size 8589934592",
            "--batch-size 8589934592",
            Error("--batch-size must lie in [1, 2^32]"),
        ),
        ill(
            "--batch-size 1 --chains 1",
            "--batch-size 1 --chains 1 --threads 1",
            Accept("2 batches"),
        ),
        ill(
            "--rr-weight 0",
            "--rr-weight 0",
            Error("--rr-weight must lie in (0, 1]"),
        ),
        ill(
            "--rr-weight 2",
            "--rr-weight 2",
            Error("--rr-weight must lie in (0, 1], got 2"),
        ),
        ill(
            "--rr-weight nan",
            "--rr-weight nan",
            Error("--rr-weight must lie in (0, 1]"),
        ),
        ill(
            "--rr-weight 1e-300",
            &format!("--rr-weight 1e-300 {run}"),
            Accept("E_avg"),
        ),
        ill(
            "--near-radius -1",
            "--near-radius -1",
            Error("--near-radius"),
        ),
        ill(
            "--near-radius abc",
            "--near-radius abc",
            Error("--near-radius must be `auto` or a length"),
        ),
        ill(
            "--near-radius inf",
            "--near-radius inf",
            Error("--near-radius must be `auto` or a finite length"),
        ),
        ill(
            "--near-radius 1e300",
            &format!("--near-radius 1e300 {run}"),
            Accept("E_avg"),
        ),
        ill(
            "--near-paths 0 (the split is off)",
            &format!("--near-paths 0 {run}"),
            Accept("E_avg 44.1439"),
        ),
        ill("--estimator foo", "--estimator foo", Error("--estimator")),
        ill(
            "--estimator backward with --near-radius",
            "--estimator backward --near-radius 0.1",
            Error("--near-radius applies to the local estimator only"),
        ),
        ill(
            "--estimator backward",
            &format!("--estimator backward {run}"),
            Accept("E_avg"),
        ),
        ill(
            "--views without --views-out",
            "--views {v}",
            Error("--views-out"),
        ),
        ill(
            "--out over the scene",
            "--out {s}",
            Error("would overwrite the input"),
        ),
        ill(
            "--out over the points",
            "--out {p}",
            Error("would overwrite the input"),
        ),
        ill(
            "--out equal to --views-out",
            "--views {v} --views-out {d}/E.csv",
            Error("is the same file as --out"),
        ),
        ill(
            "--out in a missing folder",
            "--out {d}/no/E.csv",
            Error("does not exist"),
        ),
        ill("--out a folder", "--out {d}", Error("is a folder")),
        ill(
            "--out - (standard output)",
            &format!("--out - {run}"),
            Accept("a,0,0,0.75,0,0,1,5"),
        ),
        cli(
            "--scene missing",
            "illuminance --points {p} --out {d}/E.csv",
            Error("--scene"),
        ),
        cli(
            "unknown option",
            "illuminance --scene {s} --points {p} --out {d}/E.csv --colour red",
            Error("--colour"),
        ),
        cli(
            "unknown subcommand",
            "illuminate --scene {s}",
            Error("illuminate"),
        ),
        cli("no arguments", "", Error("Usage")),
        lum(
            "--views and --fan-at together",
            "--views {v} --fan-at 0,0,0,0,0,1 --fan 10,10",
            Error("--fan-at"),
        ),
        lum(
            "--fan-at without --fan",
            "--fan-at 0,0,0,0,0,1",
            Error("--fan"),
        ),
        lum(
            "--fan 0,10",
            "--fan-at 0,0,0,0,0,1 --fan 0,10",
            Error("--fan: steps must lie in (0, 90] degrees"),
        ),
        lum(
            "--fan 0.01,0.01 (too many views)",
            "--fan-at 0,0,0,0,0,1 --fan 0.01,0.01",
            Error("at most 4000000"),
        ),
        lum(
            "--fan-at with five numbers",
            "--fan-at 0,0,0,0,1 --fan 10,10",
            Error("--fan-at"),
        ),
        lum(
            "--fan-at zero normal",
            "--fan-at 0,0,0,0,0,0 --fan 10,10",
            Error("--fan-at: the normal has zero length"),
        ),
        // A normal of 1e200 gave a zero vector (its square overflowed):
        // every view horizontal, L = 0, flagged ok.
        lum(
            "--fan-at normal 1e200",
            "--fan-at 0,0,0.5,0,0,1e200 --fan 30,90",
            Accept("12 rows written"),
        ),
        lum(
            "--fan-at point 1e300",
            "--fan-at 0,0,1e300,0,0,1 --fan 30,90",
            Error("--fan-at: the point must lie within"),
        ),
        lum(
            "--fan-at nan",
            "--fan-at 0,nan,0,0,0,1 --fan 10,10",
            Error("--fan-at"),
        ),
        lum(
            "--plot and --out both -",
            "--fan-at 0,0,0.1,0,0,1 --fan 30,30 --out - --plot -",
            Error("both write to standard output"),
        ),
        lum(
            "--plot-part without --plot",
            "--views {v} --plot-part indirect",
            Error("--plot"),
        ),
        lum(
            "--points without --points-out",
            "--views {v} --points {p}",
            Error("--points-out"),
        ),
        lum(
            "--points-out over the views",
            "--views {v} --points {p} --points-out {v}",
            Error("would overwrite the input"),
        ),
        lum(
            "views and points in one run",
            &format!("--views {{v}} --points {{p}} --points-out {{d}}/E.csv {run}"),
            Accept("3 rows read from"),
        ),
        render(
            "--width 0",
            "--eye 0,-1,1.5 --look 0,0,1.5 --width 0 --out {d}/r.png",
            Error("--width"),
        ),
        render(
            "--height 0",
            "--eye 0,-1,1.5 --look 0,0,1.5 --height 0 --out {d}/r.png",
            Error("--height"),
        ),
        render(
            "--fov 0",
            "--eye 0,-1,1.5 --look 0,0,1.5 --fov 0 --out {d}/r.png",
            Error("--fov"),
        ),
        render(
            "--fov 180",
            "--eye 0,-1,1.5 --look 0,0,1.5 --fov 180 --out {d}/r.png",
            Error("--fov"),
        ),
        render(
            "--fov nan",
            "--eye 0,-1,1.5 --look 0,0,1.5 --fov nan --out {d}/r.png",
            Error("--fov"),
        ),
        render(
            "--eye equal to --look",
            "--eye 0,0,1.5 --look 0,0,1.5 --out {d}/r.png",
            Error("--look must differ from --eye"),
        ),
        render(
            "--up along the view",
            "--eye 0,0,1 --look 0,0,2 --out {d}/r.png",
            Error("--up"),
        ),
        render(
            "--eye with two numbers",
            "--eye 0,1 --look 0,0,1.5 --out {d}/r.png",
            Error("--eye"),
        ),
        render(
            "--eye 1e300 (shown short)",
            "--eye 1e300,0,1 --look 0,0,1.5 --out {d}/r.png",
            Error("--eye"),
        ),
        render(
            "--out -",
            "--eye 0,-1,1.5 --look 0,0,1.5 --out -",
            Error("--out"),
        ),
        render(
            "--lens-samples 2",
            "--eye 0,-1,1.5 --look 0,0,1.5 --aperture 0.01 --lens-samples 2 --out {d}/r.png",
            Error("--lens-samples"),
        ),
        render(
            "--aperture -1",
            "--eye 0,-1,1.5 --look 0,0,1.5 --aperture -1 --out {d}/r.png",
            Error("--aperture"),
        ),
        render(
            "--focus 0",
            "--eye 0,-1,1.5 --look 0,0,1.5 --aperture 0.01 --focus 0 --out {d}/r.png",
            Error("--focus"),
        ),
        render(
            "--exposure -1",
            "--eye 0,-1,1.5 --look 0,0,1.5 --exposure -1 --out {d}/r.png",
            Error("--exposure"),
        ),
        render(
            "--exposure abc",
            "--eye 0,-1,1.5 --look 0,0,1.5 --exposure abc --out {d}/r.png",
            Error("--exposure"),
        ),
        render(
            "100000 x 100000 pixels",
            "--eye 0,-1,1.5 --look 0,0,1.5 --width 100000 --height 100000 --out {d}/r.png",
            Error("--width x --height must be positive and at most 4 Mpixel, got 100000 x 100000"),
        ),
        render(
            "a plain 4 x 3 render",
            "--eye 0,-1,1.5 --look 0,0,1.5 --threads 1 --out {d}/r.png",
            Accept("wrote"),
        ),
        cli(
            "sobolev --h1 0",
            "sobolev --h1 0 --plane 1 --r 0,1",
            Error("h1"),
        ),
        cli(
            "sobolev --rho1 1.5",
            "sobolev --rho1 1.5 --plane 1 --r 0,1",
            Error("rho1"),
        ),
        cli(
            "sobolev --rho1 1 --rho2 1 (no absorption)",
            "sobolev --rho1 1 --rho2 1 --plane 1 --r 0,1",
            Error("rho"),
        ),
        cli(
            "sobolev --plane 3",
            "sobolev --plane 3 --r 0,1",
            Error("--plane"),
        ),
        cli(
            "sobolev --r 0:3:0",
            "sobolev --plane 1 --r 0:3:0",
            Error("needs step > 0"),
        ),
        cli(
            "sobolev --r 3:0:0.1",
            "sobolev --plane 1 --r 3:0:0.1",
            Error("stop >= start"),
        ),
        cli(
            "sobolev --r 0:1e9:1e-9 (too many)",
            "sobolev --plane 1 --r 0:1e9:1e-9",
            Error("--r"),
        ),
        cli("sobolev --r a,b", "sobolev --plane 1 --r a,b", Error("--r")),
        cli("sobolev --r -1", "sobolev --plane 1 --r -1", Error("--r")),
        cli(
            "sobolev --orders 1000",
            "sobolev --plane 1 --r 0 --orders 1000",
            Accept("E_order1000"),
        ),
        cli(
            "sobolev --r 1e300",
            "sobolev --plane 1 --r 1e300",
            Accept("1e300"),
        ),
        cli(
            "sh-fit --degree 101",
            "sh-fit {m} --degree 101 --out {d}/c2.csv",
            Error("--degree 101: at most 100"),
        ),
        cli(
            "sh-fit --samples 3e6",
            "sh-fit {m} --degree 2 --samples 3000000 --out {d}/c2.csv",
            Error("--samples 3000000: at most"),
        ),
        cli(
            "sh-fit --samples below (L + 1)^2",
            "sh-fit {m} --degree 4 --samples 3 --out {d}/c2.csv",
            Error("--samples must be at least"),
        ),
        cli(
            "sh-fit --center with nan",
            "sh-fit {m} --degree 2 --center 0,nan,0 --out {d}/c2.csv",
            Error("--center"),
        ),
        cli(
            "sh-fit --center outside the mesh",
            "sh-fit {m} --degree 2 --center 5,5,5 --out {d}/c2.csv",
            Error("--center"),
        ),
        cli(
            "sh-fit of a missing mesh",
            "sh-fit {d}/none.obj --degree 2 --out {d}/c2.csv",
            Error("none.obj"),
        ),
        cli(
            "sh-fit --out over the mesh",
            "sh-fit {m} --degree 2 --out {m}",
            Error("would overwrite the input"),
        ),
        cli(
            "sh-fit --compare -1",
            "sh-fit {m} --degree 2 --out {d}/c2.csv --compare -1",
            Error("--compare"),
        ),
        cli(
            "sh-fit of a tetrahedron",
            "sh-fit {m} --degree 2 --out {d}/c2.csv",
            Accept("fit residual"),
        ),
        cli(
            "photometry --plot over the file",
            "photometry {ies} --plot {ies}",
            Error("would overwrite the input"),
        ),
        cli(
            "photometry --plot in a missing folder",
            "photometry {ies} --plot {d}/no/p.svg",
            Error("does not exist"),
        ),
        cli(
            "photometry of a scene file",
            "photometry {s}",
            Error("unknown photometric format"),
        ),
        cli("bench --points 0", "bench --points 0", Error("at least 1")),
        cli(
            "bench --points abc",
            "bench --points abc",
            Error("--points"),
        ),
        cli(
            "bench --time -1",
            "bench --points 1 --time -1",
            Error("--time"),
        ),
        cli(
            "validate with an unknown case",
            "validate nothing",
            Error("nothing"),
        ),
        cli(
            "validate box --rho 1.5",
            "validate box --rho 1.5 --chains 1000 --report {d}/rep",
            Error("--rho must lie in [0, 1)"),
        ),
        cli(
            "validate box --rho -0.5",
            "validate box --rho -0.5 --chains 1000 --report {d}/rep",
            Error("--rho must lie in [0, 1)"),
        ),
        cli(
            "validate box --chains 0",
            "validate box --chains 0 --report {d}/rep",
            Error("--chains must be at least 64"),
        ),
        cli(
            "validate box --report a file",
            "validate box --chains 1000 --report {p}",
            Error("--report"),
        ),
        cli(
            "validate sobolev --rho1 2",
            "validate sobolev --rho1 2 --report {d}/rep",
            Error("rho1 = 2 must lie in [0, 1]"),
        ),
        cli(
            "validate sobolev --report a file",
            "validate sobolev --report {s}",
            Error("--report"),
        ),
    ]
}

fn all_cases() -> Vec<Case> {
    let mut c = scene_cases();
    c.extend(points_cases());
    c.extend(views_cases());
    c.extend(obj_cases());
    c.extend(sh_cases());
    c.extend(ies_cases());
    c.extend(ldt_cases());
    c.extend(cli_cases());
    c
}

/// The result columns compared by `Same`.
fn results(out: &str) -> Vec<Vec<String>> {
    ["E", "E_stderr", "L", "L_stderr"]
        .iter()
        .map(|c| column(out, c))
        .filter(|c| !c.is_empty())
        .collect()
}

/// `s` with the wall time of a run summary (`0.006 s on 1 thread(s)`)
/// written `T s`, as it varies from run to run.
fn untimed(s: &str) -> String {
    match s.find(" s on ") {
        Some(k) => {
            let start = s[..k]
                .rfind(|c: char| !(c.is_ascii_digit() || c == '.'))
                .map_or(0, |i| i + 1);
            format!("{}T{}", &s[..start], &s[k..])
        }
        None => s.to_string(),
    }
}

/// The longest run of digits in `s`.
fn longest_digit_run(s: &str) -> usize {
    s.split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0)
}

fn md_escape(s: &str) -> String {
    s.replace('|', "\\|").replace('\n', " ")
}

/// Check one case; returns the markdown cells (expected, what it gets now)
/// or what is wrong.
fn check(case: &Case, r: &Ran, plain: Option<&Ran>, dir: &str) -> Result<(String, String), String> {
    let all = format!(
        "{}\n{}\n{}",
        r.stdout,
        r.stderr,
        r.out.as_deref().unwrap_or("")
    );
    if r.stderr.contains("panicked") || !matches!(r.code, Some(0..=2)) {
        return Err(format!("panic or signal (exit {:?}): {}", r.code, r.stderr));
    }
    // Item 15 of issue 12: no message repeats the operating system's text,
    // prints a vector's Debug form, or writes a number with dozens of digits.
    let said = format!("{}\n{}", r.stdout, r.stderr);
    if said.matches("(os error").count() > 1 {
        return Err(format!("the OS text twice: {}", r.stderr));
    }
    if said.contains("DVec3") {
        return Err(format!("a DVec3 printed: {said}"));
    }
    if longest_digit_run(&said) > 20 {
        return Err(format!("a number of more than 20 digits: {said}"));
    }
    let ok = r.code == Some(0);
    if ok {
        if let Some(w) = non_finite(&all) {
            return Err(format!("`{w}` in the output: {all}"));
        }
    } else if let Some(o) = &r.out
        && !o.is_empty()
        && case.ch != Ch::Cli
    {
        return Err("a failed run left its output file".into());
    }
    let clean = |s: &str| md_escape(&untimed(&s.replace(dir, "DIR").replace("lumest: ", "")));
    let err = error_line(&r.stderr);
    match case.expect {
        Expect::Error(want) => {
            if ok {
                return Err(format!(
                    "accepted, expected an error with `{want}`:\n{}",
                    r.stderr
                ));
            }
            if !r.stderr.contains(want) {
                return Err(format!("error without `{want}`: {}", r.stderr));
            }
            if let Some(f) = case.ch.file()
                && !r.stderr.contains(f)
            {
                return Err(format!("error does not name {f}: {}", r.stderr));
            }
            Ok((
                format!("error containing `{}`", md_escape(want)),
                clean(err),
            ))
        }
        Expect::Warn(want) => {
            if !ok || !r.stderr.contains(want) {
                return Err(format!("expected a run with `{want}`: {}", r.stderr));
            }
            Ok((
                format!("runs, saying `{}`", md_escape(want)),
                clean(line_with(&r.stderr, want)),
            ))
        }
        Expect::Flag(want) => {
            let out = r.out.as_deref().unwrap_or("");
            let flags: Vec<String> = ["E_flag", "L_flag"]
                .iter()
                .flat_map(|c| column(out, c))
                .collect();
            if !ok || !flags.iter().any(|f| f.contains(want)) {
                return Err(format!(
                    "expected flag `{want}`, got {flags:?}: {}",
                    r.stderr
                ));
            }
            let mut distinct = flags.clone();
            distinct.dedup();
            Ok((
                format!("runs, flag `{want}`"),
                format!("flags {}", md_escape(&distinct.join(", "))),
            ))
        }
        Expect::Same => {
            let plain = plain.expect("a plain run for the channel");
            let (a, b) = (
                results(r.out.as_deref().unwrap_or(&r.stdout)),
                results(plain.out.as_deref().unwrap_or(&plain.stdout)),
            );
            if !ok || a.is_empty() || a != b {
                return Err(format!(
                    "expected the plain input's results:\n{a:?}\nvs\n{b:?}\n{}",
                    r.stderr
                ));
            }
            Ok((
                "runs, same results as the plain input".into(),
                format!(
                    "same E/L and standard errors as the plain input (first: {})",
                    a[0][0]
                ),
            ))
        }
        Expect::Accept(want) => {
            if !ok || !all.contains(want) {
                return Err(format!("expected a run with `{want}`:\n{all}"));
            }
            // A run stopped by --time is not reproducible: only what it
            // must say is recorded.
            let now = if case.args.iter().any(|a| a == "--time") {
                format!(
                    "... {} ... (a timed run: the rest of the line varies)",
                    md_escape(want)
                )
            } else {
                clean(line_with(&all, want))
            };
            Ok((format!("runs, with `{}`", md_escape(want)), now))
        }
    }
}

/// A case's markdown cells (expected, what it gets now), or what is wrong.
type Checked = Result<(String, String), String>;

/// The plain input of each channel, run once, for `Same`.
fn plain_case(ch: Ch) -> Case {
    let body = match ch {
        Ch::Scene => text(SCENE),
        Ch::Points => text(POINTS),
        Ch::Views => text(VIEWS),
        Ch::Obj => text(OBJ),
        Ch::Sh => text(COEFFS),
        Ch::Ies => text(IES),
        Ch::Ldt => text(ldt()),
        Ch::Cli => Body::Missing,
    };
    case(ch, "plain", body, Expect::Same)
}

#[test]
fn bad_inputs_get_what_the_table_says() {
    let cases = all_cases();
    let root = tempfile::tempdir().unwrap();
    let plain: BTreeMap<Ch, Ran> = [Ch::Scene, Ch::Points, Ch::Views, Ch::Obj, Ch::Sh]
        .into_iter()
        .map(|ch| {
            let d = root.path().join(format!("plain-{ch:?}"));
            std::fs::create_dir(&d).unwrap();
            (ch, run(&d, &plain_case(ch)))
        })
        .collect();
    let next = AtomicUsize::new(0);
    let rows: Mutex<Vec<(usize, Checked)>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(k) else { break };
                    let d = root.path().join(format!("case{k:03}"));
                    std::fs::create_dir(&d).unwrap();
                    let r = run(&d, case);
                    let checked = check(case, &r, plain.get(&case.ch), &d.to_string_lossy());
                    rows.lock().unwrap().push((k, checked));
                }
            });
        }
    });
    let mut rows = rows.into_inner().unwrap();
    rows.sort_by_key(|r| r.0);
    let mut failures = Vec::new();
    let mut md = String::from(
        "# Bad and unusual inputs: what each gets now\n\n\
         Written by `tests/bad_inputs.rs` (the table of cases is there); the test fails when this file\n\
         differs from what the runs give. Rewrite it with\n\
         `LUMEST_BLESS=1 cargo test --release --test bad_inputs`.\n\n\
         Plain inputs, which each case changes in one place: a 4 x 4 x 3 m room (`box`, reflectance 0.5)\n\
         with a 100 cd point light at (0, 0, 2.5) (`s.toml`); three points 0.75 m above the floor\n\
         (`p.csv`); two views (`v.csv`); a tetrahedron (`m.obj`, added to the scene for the OBJ cases);\n\
         an SH object's coefficients (`c.csv`, added to the scene for the SH cases); a three-angle IES\n\
         file (`f.ies`) and `data/photometry/isym1.ldt` (`f.ldt`), read by `lumest photometry`. Monte\n\
         Carlo runs take `--chains 1024 --batch-size 32 --threads 1`. Every case must also exit without a\n\
         panic and put no NaN or infinity in any output. `DIR` is the case's folder.\n\n",
    );
    let mut counts: BTreeMap<(&str, &str), usize> = BTreeMap::new();
    let mut table = String::from(
        "| # | channel | input | expected | what lumest does now |\n|---|---|---|---|---|\n",
    );
    for (k, res) in &rows {
        let case = &cases[*k];
        let class = match case.expect {
            Expect::Error(_) => "error",
            Expect::Warn(_) => "runs with a warning",
            Expect::Flag(_) => "runs with a flag",
            Expect::Same => "runs, same answer",
            Expect::Accept(_) => "runs, given answer",
        };
        *counts.entry((case.ch.name(), class)).or_default() += 1;
        match res {
            Ok((expected, now)) => {
                table += &format!(
                    "| {} | {} | {} | {} | {} |\n",
                    k + 1,
                    case.ch.name(),
                    md_escape(&case.what),
                    expected,
                    now
                );
            }
            Err(e) => failures.push(format!(
                "case {} ({}: {}): {e}",
                k + 1,
                case.ch.name(),
                case.what
            )),
        }
    }
    md += &format!(
        "{} cases.\n\n| channel | outcome | cases |\n|---|---|---|\n",
        cases.len()
    );
    for ((ch, class), n) in &counts {
        md += &format!("| {ch} | {class} | {n} |\n");
    }
    md += "\n";
    md += &table;
    assert!(
        failures.is_empty(),
        "{} of {} cases fail:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n\n")
    );
    assert!(cases.len() >= 200, "{} cases", cases.len());
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/validation/bad_inputs.md");
    if std::env::var_os("LUMEST_BLESS").is_some() {
        std::fs::write(path, &md).unwrap();
    } else {
        let now = std::fs::read_to_string(path).unwrap_or_default();
        assert!(
            now == md,
            "validation/bad_inputs.md is stale; rewrite it with LUMEST_BLESS=1 cargo test --release --test bad_inputs"
        );
    }
}
