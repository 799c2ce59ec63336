//! Scenes: description (as written) -> validated and compiled scene.
//!
//! Two strict stages: [`desc`] is the file as written (unknown keys rejected),
//! [`load`] validates every value with its line and compiles the scene. This is
//! the only place where user units would be converted and where it is decided
//! what the scene needs (for example, a planes-only scene never builds a BVH).

pub mod compile;
pub mod desc;
pub mod world;

pub use world::{
    AUTO_MIN_SHAPES, Accel, BuildError, MAX_COORD, MAX_INTENSITY, MAX_PLANES, MIN_INTENSITY, Scene,
    SceneSummary, ShapeRef, Sides, Surface, SurfaceSpec,
};

use std::path::{Path, PathBuf};

/// An error in a scene file, with the file, line, column and field.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read. The operating system's reason is part
    /// of the message and deliberately not an error source: `{:#}` would
    /// print it twice.
    #[error("{file}: cannot read scene file: {reason}")]
    Io {
        file: PathBuf,
        reason: std::io::Error,
    },
    /// The TOML is malformed, has an unknown key, a missing or mistyped field.
    #[error("{file}:{line}:{column}: {message}")]
    Syntax {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// A value is out of its valid range.
    #[error("{file}:{line}:{column}: field `{field}`: {message}")]
    Invalid {
        file: PathBuf,
        line: usize,
        column: usize,
        field: String,
        message: String,
    },
}

/// Read, validate and compile a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let src = read_scene(path)?;
    parse(&src, path)
}

/// A scene file's text; not UTF-8, the line and column of its first bad
/// byte (it said only that the stream was not valid UTF-8).
fn read_scene(path: &Path) -> Result<String, SceneError> {
    let bytes = std::fs::read(path).map_err(|reason| SceneError::Io {
        file: path.to_path_buf(),
        reason,
    })?;
    crate::io::csvio::utf8_text(bytes).map_err(|(line, column)| SceneError::Syntax {
        file: path.to_path_buf(),
        line,
        column,
        message: "not UTF-8 text: save the file as UTF-8".into(),
    })
}

/// Light kinds whose light is the sky's for a daylight factor: `sky` and
/// `environment` (CIE S 017, daylight factor: the light of a sky of
/// assumed or known luminance distribution, direct sunlight excluded).
pub const SKY_KINDS: [&str; 2] = ["sky", "environment"];

/// Light kinds that are also surfaces (they block and reflect light):
/// area sources.
const BODY_KINDS: [&str; 2] = ["rectangle", "disc"];

/// A scene for daylight factors: read and validated whole (every light, so
/// that an error in one is reported as by [`load`]), then compiled with
/// its [`SKY_KINDS`] lights alone emitting: the others (`sun` and
/// `distant` lights, whose parallel beams are direct sunlight, and
/// electric lights) are left out, except that an area source keeps its
/// surface with zero luminance. Returns the scene, the lights left out in
/// words, and the number of sky lights kept (0: the scene returned is the
/// whole one, for the caller to refuse).
pub fn load_sky_only(path: &Path) -> Result<(Scene, Vec<String>, usize), SceneError> {
    let src = read_scene(path)?;
    let mut desc = parse_desc(&src, path)?;
    let ctx = compile::SourceCtx {
        src: &src,
        file: path,
    };
    let whole = compile::compile(&desc, &ctx)?;
    let mut left_out = Vec::new();
    let mut kept = 0;
    let mut k = 0;
    desc.light.retain_mut(|l| {
        k += 1;
        let span = l.span();
        let l = l.get_mut();
        let kind = l.kind.get_ref().clone();
        if SKY_KINDS.contains(&kind.as_str()) {
            kept += 1;
            return true;
        }
        let name = match &l.name {
            Some(n) => format!("`{kind}` light '{}'", n.get_ref()),
            None => format!("`{kind}` light #{k} of the file"),
        };
        // An area source is also a surface (it blocks and reflects the
        // sky's light): switched off, not removed.
        let body = BODY_KINDS.contains(&kind.as_str());
        if body {
            l.luminance = Some(toml::Spanned::new(span, 0.0));
            l.flux = None;
            left_out.push(format!("{name} (switched off; its surface stays)"));
        } else {
            left_out.push(name);
        }
        body
    });
    if kept == 0 {
        // No sky; the caller refuses the run.
        return Ok((whole, left_out, 0));
    }
    Ok((compile::compile(&desc, &ctx)?, left_out, kept))
}

/// The key of the `key = value` whose value starts at byte `at` (the last
/// `key =` before `at` on its line, also inside an inline table), if any.
fn key_before(src: &str, at: usize) -> Option<&str> {
    let before = src.get(..at)?;
    let line = &before[before.rfind('\n').map_or(0, |i| i + 1)..];
    let key = line[..line.rfind('=')?].trim_end();
    let start = key
        .rfind(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '-'))
        .map_or(0, |i| i + 1);
    Some(&key[start..]).filter(|k| !k.is_empty())
}

/// The files a scene file refers to (meshes, SH coefficient files,
/// photometric files), resolved relative to the scene's folder, for the
/// output check: an output must not overwrite them. A scene that cannot be
/// read or parsed refers to nothing here; loading it reports why.
pub fn referenced_files(path: &Path) -> Vec<PathBuf> {
    let Ok(src) = std::fs::read_to_string(path) else {
        return Vec::new();
    };
    let Ok(desc) = toml::from_str::<desc::SceneDesc>(&src) else {
        return Vec::new();
    };
    let ctx = compile::SourceCtx {
        src: &src,
        file: path,
    };
    let surfaces = desc
        .surface
        .iter()
        .filter_map(|s| s.get_ref().file.as_ref());
    let lights = desc.light.iter().filter_map(|l| l.get_ref().file.as_ref());
    surfaces
        .chain(lights)
        .map(|f| ctx.relative(f.get_ref()))
        .collect()
}

/// Validate and compile a scene from TOML text; `file` is used in messages.
pub fn parse(src: &str, file: &Path) -> Result<Scene, SceneError> {
    let desc = parse_desc(src, file)?;
    compile::compile(&desc, &compile::SourceCtx { src, file })
}

/// The tables of scene TOML text, not yet validated (`file` names it in
/// messages): a syntax error or a value of the wrong type names the line,
/// column and key.
pub(crate) fn parse_desc(src: &str, file: &Path) -> Result<desc::SceneDesc, SceneError> {
    let ctx = compile::SourceCtx { src, file };
    toml::from_str(src).map_err(|e| {
        let at = e.span().map_or(0, |s| s.start);
        let (line, column) = ctx.line_col(at);
        let message = e.message().trim();
        // A value of the wrong type or length: name its key, as the
        // validation stage does ("invalid type: string "1", expected f64").
        let mut message = match key_before(src, at) {
            Some(key) if !message.contains("field `") => format!("field `{key}`: {message}"),
            _ => message.to_string(),
        };
        // `[surface]` after `[[surface]]` is read as a second table of the
        // same name: say what was meant.
        let before = src[..at.min(src.len())].rsplit('\n').next().unwrap_or("");
        let rest = &src[at.min(src.len()) - before.len()..];
        // A key given twice: name it (the parser's message does not).
        if message == "duplicate key"
            && let Some(key) = rest
                .lines()
                .next()
                .and_then(|l| l.split_once('='))
                .map(|(k, _)| k.trim())
                .filter(|k| !k.is_empty())
        {
            message = format!("duplicate key `{key}` (a key may be given once per table)");
        }
        if let Some(table) = ["surface", "light"]
            .into_iter()
            .find(|t| rest.trim_start().starts_with(&format!("[{t}]")))
        {
            message += &format!(
                " (each {table} is an array-of-tables entry: write `[[{table}]]` with double brackets)"
            );
        }
        SceneError::Syntax {
            file: file.to_path_buf(),
            line,
            column,
            message,
        }
    })
}
