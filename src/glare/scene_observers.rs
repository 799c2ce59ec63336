//! Glare observers written in the scene file, `[[observer]]` tables:
//!
//! ```toml
//! [[observer]]
//! name = "desk 1 looking along the room"   # optional
//! eye = [0.6, 1.4, 1.2]                     # \[m\]
//! view = [1, 0, 0]                          # line of sight, not vertical
//! ```
//!
//! `lumest glare --scene S` rates them when no `--observers` CSV is given;
//! they become the rows of a view table with the columns `name, x, y, z,
//! dx, dy, dz`, each row's line its table's line in the scene file.

use crate::grid::invalid;
use crate::io::csvio::ViewTable;
use crate::io::format_number;
use crate::scene::SceneError;
use crate::scene::compile::SourceCtx;
use glam::DVec3;
use std::path::Path;

/// The `[[observer]]` tables of the scene file at `path` as a view table
/// (empty when there are none). Errors name the file, line and field: an
/// eye or line of sight that is not finite, a zero or vertical line of
/// sight.
pub fn scene_observers(path: &Path) -> Result<ViewTable, SceneError> {
    let src = std::fs::read_to_string(path).map_err(|reason| SceneError::Io {
        file: path.to_path_buf(),
        reason,
    })?;
    let ctx = SourceCtx {
        src: &src,
        file: path,
    };
    let desc = crate::scene::parse_desc(&src, path)?;
    let invalid = |span, field: &str, message: &str| invalid(&ctx, span, field, message);
    let mut table = ViewTable {
        headers: ["name", "x", "y", "z", "dx", "dy", "dz"]
            .map(String::from)
            .to_vec(),
        rows: Vec::new(),
        lines: Vec::new(),
        comment_lines: 0,
        views: Vec::new(),
    };
    for (k, o) in desc.observer.iter().enumerate() {
        let o = o.get_ref();
        let eye = DVec3::from_array(o.eye.get_ref().0);
        let view = DVec3::from_array(o.view.get_ref().0);
        if !eye.is_finite() {
            return Err(invalid(o.eye.span(), "eye", "must be finite [m]"));
        }
        let Some(unit) = crate::geometry::unit_direction(view) else {
            return Err(invalid(
                o.view.span(),
                "view",
                "must be a finite, non-zero direction",
            ));
        };
        if unit.z.abs() > 1.0 - 1e-6 {
            return Err(invalid(
                o.view.span(),
                "view",
                "the line of sight must not be vertical (the position index is measured from \
                 the observer's up direction)",
            ));
        }
        let name = o
            .name
            .as_ref()
            .map_or_else(|| format!("observer {}", k + 1), |n| n.get_ref().clone());
        let mut row = vec![name];
        row.extend(
            eye.to_array()
                .iter()
                .chain(&view.to_array())
                .map(|v| format_number(*v)),
        );
        table.rows.push(row);
        table.lines.push(ctx.line_col(o.eye.span().start).0 as u64);
        table.views.push((eye, view));
    }
    Ok(table)
}
