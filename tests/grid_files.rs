//! `[[grid]]` tables: the points they make (EN 12464-1 cells, borders,
//! named surfaces and box faces, discs, EN 13201-3 road fields) and the
//! errors bad keys get (file, line and field).

use glam::DVec3;
use lumest::grid::{Grid, parse};
use std::path::Path;

const ROOM: &str = r#"[[surface]]
type = "box"
name = "room"
min = [0, 0, 0]
max = [6, 4, 2.8]
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
type = "box"
name = "desk"
min = [1, 1, 0]
max = [2.6, 1.8, 0.75]
normals = "outward"
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
type = "disc"
name = "table"
center = [4.8, 3.1, 0.72]
normal = [0, 0, 1]
radius = 0.55
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
type = "rectangle"
name = "board"
corner = [5.99, 0.8, 0.9]
edge1 = [0, 1.8, 0]
edge2 = [0, 0, 1.2]
sides = "back"
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "point"
position = [3, 2, 2.5]
intensity = 100
"#;

fn grids(extra: &str) -> Result<Vec<Grid>, String> {
    let src = format!("{ROOM}\n{extra}");
    parse(&src, Path::new("S.toml")).map_err(|e| e.to_string())
}

fn one(extra: &str) -> Grid {
    let mut g = grids(extra).unwrap();
    assert_eq!(g.len(), 1);
    g.remove(0)
}

/// Line of `needle` in the scene text built from `extra` (1-based).
fn line_of(extra: &str, needle: &str) -> usize {
    let before = format!("{ROOM}\n").lines().count();
    before + extra.lines().position(|l| l.contains(needle)).unwrap() + 1
}

/// The office's work plane: the floor face offset 0.75 m, a 0.5 m border:
/// a 5 m x 3 m area, d = 5 m, p = 0.616 m, 9 x 6 cells of 0.556 m x 0.5 m.
#[test]
fn work_plane_on_the_floor_face() {
    let g = one(
        "[[grid]]\nname = \"work plane\"\nsurface = \"room.z_min\"\noffset = 0.75\nborder = 0.5\nem = 500\nu0 = 0.6\nmaintenance_factor = 0.8\n",
    );
    assert_eq!(g.cells, (9, 6));
    assert_eq!(g.points.len(), 54);
    assert!((g.area() - 15.0).abs() < 1e-12);
    assert_eq!(
        (g.em, g.u0, g.maintenance_factor),
        (Some(500.0), Some(0.6), 0.8)
    );
    assert_eq!(g.receiver, "planar");
    for q in &g.points {
        assert_eq!(q.n, DVec3::Z);
        assert!((q.p.z - 0.75).abs() < 1e-15);
        // Cell centres: half a cell inside the border.
        assert!(q.p.x >= 0.5 + 0.27 && q.p.x <= 5.5 - 0.27, "{:?}", q.p);
        assert!(q.p.y >= 0.5 + 0.24 && q.p.y <= 3.5 - 0.24, "{:?}", q.p);
        assert!((q.area - 5.0 / 9.0 * 0.5).abs() < 1e-15);
    }
    // The first point: the centre of the first cell.
    assert!((g.points[0].p - DVec3::new(0.5 + 5.0 / 18.0, 0.75, 0.75)).length() < 1e-12);
}

/// Without a border the whole floor: 6 x 4 m, 9 x 6 cells of 0.667 m.
#[test]
fn border_changes_the_area_and_the_cells() {
    let g = one("[[grid]]\nname = \"floor\"\nsurface = \"room.z_min\"\n");
    assert_eq!(g.cells, (9, 6));
    assert!((g.area() - 24.0).abs() < 1e-12);
    assert!((g.points[0].p - DVec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0)).length() < 1e-12);
    // A border of 1.9 m leaves a 2.2 m x 0.2 m strip; 2 m leaves nothing.
    let g = one("[[grid]]\nname = \"strip\"\nsurface = \"room.z_min\"\nborder = 1.9\n");
    assert!((g.area() - 2.2 * 0.2).abs() < 1e-12);
    let extra = "[[grid]]\nname = \"none\"\nsurface = \"room.z_min\"\nborder = 2\n";
    let e = grids(extra).unwrap_err();
    let line = line_of(extra, "border = 2");
    assert!(e.starts_with(&format!("S.toml:{line}:")), "{e}");
    assert!(
        e.contains("field `border`") && e.contains("leaves nothing"),
        "{e}"
    );
}

/// Box faces face the reflecting side: a room's ceiling faces down, a
/// desk's top up, a desk's side outward; a back-sided rectangle faces
/// `edge2 x edge1`.
#[test]
fn faces_and_named_surfaces() {
    let g = one("[[grid]]\nname = \"c\"\nsurface = \"room.z_max\"\noffset = 0.1\nspacing = 1\n");
    assert!(
        g.points
            .iter()
            .all(|q| q.n == -DVec3::Z && (q.p.z - 2.7).abs() < 1e-12)
    );
    assert_eq!(g.points.len(), 24);
    let g = one("[[grid]]\nname = \"d\"\nsurface = \"desk.z_max\"\n");
    assert!(g.points.iter().all(|q| q.n == DVec3::Z && q.p.z == 0.75));
    assert!((g.area() - 1.6 * 0.8).abs() < 1e-12);
    let g = one("[[grid]]\nname = \"s\"\nsurface = \"desk.x_min\"\n");
    assert!(g.points.iter().all(|q| q.n == -DVec3::X && q.p.x == 1.0));
    let g = one("[[grid]]\nname = \"w\"\nsurface = \"room.y_max\"\nspacing = 0.5\n");
    assert!(g.points.iter().all(|q| q.n == -DVec3::Y && q.p.y == 4.0));
    assert!((g.area() - 6.0 * 2.8).abs() < 1e-12);
    let g = one("[[grid]]\nname = \"b\"\nsurface = \"board\"\n");
    assert!(g.points.iter().all(|q| q.n == -DVec3::X));
    assert!((g.area() - 1.8 * 1.2).abs() < 1e-12);
}

/// A disc keeps the cells whose centres lie on it: their area is the
/// disc's to within the cells cut by the rim.
#[test]
fn disc_grid() {
    let g = one("[[grid]]\nname = \"t\"\nsurface = \"table\"\noffset = 0.03\nspacing = 0.02\n");
    let r: f64 = 0.55;
    let cell = g.points[0].area.sqrt();
    let rim = 2.0 * std::f64::consts::PI * r * cell;
    assert!(
        (g.area() - std::f64::consts::PI * r * r).abs() < rim,
        "{}",
        g.area()
    );
    let c = DVec3::new(4.8, 3.1, 0.75);
    assert!(
        g.points
            .iter()
            .all(|q| (q.p - c).length() <= r && (q.p.z - 0.75).abs() < 1e-12)
    );
}

/// A rectangle given by its edges, and a road field: S = 36 m between
/// luminaires (N = 12, D = 3 m, first row at 1.5 m), 2 lanes of 3.5 m
/// (3 points each, d = 1.1667 m, d/2 from the lane edges).
#[test]
fn rectangle_and_road() {
    let g =
        one("[[grid]]\nname = \"r\"\ncorner = [0, 0, 1]\nedge1 = [6, 0, 0]\nedge2 = [0, 4, 0]\n");
    assert_eq!((g.cells, g.points.len()), ((9, 6), 54));
    let g = one(
        "[[grid]]\nname = \"road\"\ntype = \"road\"\ncorner = [0, 0, 0]\nedge1 = [36, 0, 0]\nedge2 = [0, 7, 0]\nlanes = 2\n",
    );
    assert_eq!(g.cells, (12, 6));
    assert_eq!(g.points.len(), 72);
    let xs: Vec<f64> = g.points[..12].iter().map(|q| q.p.x).collect();
    assert!((xs[0] - 1.5).abs() < 1e-12 && (xs[11] - 34.5).abs() < 1e-12);
    let ys: Vec<f64> = g.points.iter().step_by(12).map(|q| q.p.y).collect();
    let d = 3.5 / 3.0;
    for (k, y) in ys.iter().enumerate() {
        assert!((y - (k as f64 + 0.5) * d).abs() < 1e-12, "{ys:?}");
    }
    assert!(g.points.iter().all(|q| (q.area - 3.0 * d).abs() < 1e-12));
    // S = 25 m: N = 10.
    let g = one(
        "[[grid]]\nname = \"road\"\ntype = \"road\"\ncorner = [0, 0, 0]\nedge1 = [25, 0, 0]\nedge2 = [0, 3.5, 0]\n",
    );
    assert_eq!(g.cells, (10, 3));
    assert!(!g.rule.contains("WARNING"), "{}", g.rule);
    // A 4.5 m lane keeps d = 1.5 m; a 6 m lane (d = 2 m) breaks the
    // standard's 1.5 m across an illuminance field, and says so.
    for (w, warned) in [(4.5, false), (6.0, true)] {
        let g = one(&format!(
            "[[grid]]\nname = \"road\"\ntype = \"road\"\ncorner = [0, 0, 0]\nedge1 = [25, 0, 0]\nedge2 = [0, {w}, 0]\n"
        ));
        assert_eq!(
            g.rule.contains("WARNING: d exceeds the 1.5 m"),
            warned,
            "{}",
            g.rule
        );
    }
    // Edges the other way round: the points face the ground, and the rule
    // says so (before, only a run in which no point got light warned).
    assert!(!g.rule.contains("face down"), "{}", g.rule);
    let g = one(
        "[[grid]]\nname = \"road\"\ntype = \"road\"\ncorner = [0, 0, 0]\nedge1 = [0, 7, 0]\nedge2 = [36, 0, 0]\nlanes = 2\n",
    );
    assert!(g.points.iter().all(|q| q.n.z < 0.0));
    assert!(
        g.rule.contains("WARNING: the points face down"),
        "{}",
        g.rule
    );
}

/// Bad keys get the file, the line and the field.
#[test]
fn bad_grid_keys() {
    let cases: [(&str, &str, &str); 14] = [
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\nspacng = 1\n",
            "spacng",
            "unknown field `spacng`",
        ),
        // Behind the floor, outside the room (the run then kept 20 of its
        // 64 points at E = 0 and printed U0 = NaN).
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\noffset = -1\n",
            "offset",
            "puts the grid behind `room.z_min`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\nborder = -1\n",
            "border",
            "field `border`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\nspacing = 0\n",
            "spacing",
            "field `spacing`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\nmaintenance_factor = 1.2\n",
            "maintenance_factor",
            "field `maintenance_factor`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\nu0 = 1.5\n",
            "u0",
            "field `u0`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\nreceiver = \"cylinder\"\n",
            "receiver",
            "unknown receiver type `cylinder`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room\"\n",
            "surface",
            "name one of its faces",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"room.top\"\n",
            "surface",
            "has no face `top`",
        ),
        (
            "[[grid]]\nname = \"a\"\nsurface = \"sofa\"\n",
            "surface",
            "no surface named `sofa`",
        ),
        // The surface's own error comes before the offset's.
        (
            "[[grid]]\nname = \"a\"\nsurface = \"sofa\"\noffset = -1\n",
            "surface",
            "no surface named `sofa`",
        ),
        (
            "[[grid]]\nname = \"a\"\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [1, 1, 0]\n",
            "edge2",
            "perpendicular",
        ),
        (
            "[[grid]]\nname = \"a\"\ntype = \"road\"\ncorner = [0, 0, 0]\nedge1 = [30, 0, 0]\nedge2 = [0, 7, 0]\nlanes = 0\n",
            "lanes",
            "field `lanes`",
        ),
        (
            "[[grid]]\nname = \"a\"\ntype = \"street\"\nsurface = \"room.z_min\"\n",
            "type",
            "unknown grid type",
        ),
    ];
    for (extra, key, msg) in cases {
        let e = grids(extra).unwrap_err();
        let line = line_of(extra, &format!("{key} ="));
        assert!(e.starts_with(&format!("S.toml:{line}:")), "{key}: {e}");
        assert!(e.contains(msg), "{key}: {e}");
    }
    // A negative offset under a two-sided surface (a shelf lit from below)
    // is a place like any other.
    let shelf = "[[surface]]\ntype = \"rectangle\"\nname = \"shelf\"\ncorner = [0.5, 0.5, 1.5]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nsides = \"both\"\nmaterial = { type = \"lambertian\", reflectance = 0.5 }\n[[grid]]\nname = \"under\"\nsurface = \"shelf\"\noffset = -0.2\n";
    let g = one(shelf);
    assert!(g.points.iter().all(|q| (q.p.z - 1.3).abs() < 1e-12));
    // A rectangle named like a box face of the scene: which one is meant?
    let extra = "[[surface]]\ntype = \"rectangle\"\nname = \"room.z_min\"\ncorner = [0, 0, 1]\nedge1 = [1, 0, 0]\nedge2 = [0, 1, 0]\nmaterial = { type = \"lambertian\", reflectance = 0.5 }\n[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\n";
    let e = grids(extra).unwrap_err();
    assert!(
        e.contains("field `surface`") && e.contains("names both"),
        "{e}"
    );
    // Two grids of one name; a grid without a place.
    let extra = "[[grid]]\nname = \"a\"\nsurface = \"room.z_min\"\n[[grid]]\nname = \"a\"\nsurface = \"desk.z_max\"\n";
    let e = grids(extra).unwrap_err();
    assert!(
        e.contains("S.toml:") && e.contains("field `name`") && e.contains("unique"),
        "{e}"
    );
    // A degenerate disc (which the scene compiler refuses too) gets an error, not NaN points.
    let bad = ROOM.replace("normal = [0, 0, 1]", "normal = [0, 0, 0]")
        + "[[grid]]\nname = \"t\"\nsurface = \"table\"\n";
    let e = parse(&bad, Path::new("S.toml")).unwrap_err().to_string();
    assert!(
        e.contains("field `surface`") && e.contains("bad `center`, `normal` or `radius`"),
        "{e}"
    );
    let e = grids("[[grid]]\nname = \"a\"\n").unwrap_err();
    assert!(e.contains("field `surface`") && e.contains("corner"), "{e}");
    let e = grids("[[grid]]\nsurface = \"room.z_min\"\n").unwrap_err();
    assert!(e.contains("missing field `name`"), "{e}");
}

/// A semicylindrical grid's points face its horizontal `facing` direction
/// (the normal columns), which the illuminance command requires; other
/// grids refuse the key.
#[test]
fn semicylindrical_grids_face_their_direction() {
    let g = one(
        "[[grid]]\nname = \"s\"\nsurface = \"room.z_min\"\noffset = 1.5\n\
         receiver = \"semicylindrical\"\nfacing = [0, -2, 0]\n",
    );
    assert!(!g.points.is_empty());
    assert!(
        g.points
            .iter()
            .all(|p| p.n == -DVec3::Y && (p.p.z - 1.5).abs() < 1e-12)
    );
    let bad = [
        (
            "receiver = \"semicylindrical\"\n",
            "field `facing`: missing field",
        ),
        (
            "receiver = \"semicylindrical\"\nfacing = [0, 1, 1]\n",
            "field `facing`: must be a horizontal direction",
        ),
        (
            "facing = [1, 0, 0]\n",
            "field `facing`: only `receiver = \"semicylindrical\"`",
        ),
    ];
    for (extra, want) in bad {
        let e = grids(&format!(
            "[[grid]]\nname = \"s\"\nsurface = \"room.z_min\"\n{extra}"
        ))
        .unwrap_err();
        assert!(e.contains(want), "{extra}: {e}");
    }
}
