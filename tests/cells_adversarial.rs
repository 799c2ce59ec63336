//! Visibility cells against the full shape test in adversarial geometry
//! (review of the cell proofs): shapes far from the origin, tiny boxes,
//! receivers exactly on box face planes, cells on a box's face plane,
//! cells at grazing angles behind tilted rectangles, and points just
//! outside a cell (a collision the cell lookup puts there by rounding).
//! Every point of a cell must get from `blocked_in_cell` with the cell's
//! mask the answer of `blocked_by_shapes`.

use glam::DVec3;
use lumest::sampling::Philox4x32;
use lumest::scene::Scene;
use lumest::scene::world::CELL_DARK;

fn scene_from(name: &str, toml: &str) -> Scene {
    let dir = std::env::temp_dir().join(format!("lumest-cells-adv-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.toml");
    std::fs::write(&path, toml).unwrap();
    let s = lumest::scene::load(&path);
    std::fs::remove_dir_all(&dir).ok();
    s.unwrap()
}

/// Points of the cell: corners, centre, random points, and points one or
/// a few ulps outside it.
fn points(rng: &mut Philox4x32, (lo, hi): (DVec3, DVec3)) -> Vec<DVec3> {
    let mut out = Vec::new();
    for k in 0..8 {
        out.push(DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        ));
    }
    out.push(0.5 * (lo + hi));
    for _ in 0..24 {
        let (u, v) = (rng.next_2d(), rng.next_2d());
        out.push(lo + (hi - lo) * DVec3::new(u[0], u[1], v[0]));
    }
    // A few ulps outside (the lookup of a collision by rounding).
    let n = out.len();
    for i in 0..n {
        let q = out[i];
        let c = 0.5 * (lo + hi);
        let step = |x: f64, out_dir: f64, k: i32| {
            let mut y = x;
            for _ in 0..k {
                y = if out_dir > 0.0 {
                    y.next_up()
                } else {
                    y.next_down()
                };
            }
            y
        };
        let k = 1 + (i % 4) as i32;
        out.push(DVec3::new(
            step(q.x, q.x - c.x, k),
            step(q.y, q.y - c.y, k),
            step(q.z, q.z - c.z, k),
        ));
    }
    out
}

/// Compares the cell answer with the full test at the points of `cell`
/// for the receiver `p`; returns (pairs, dark, mismatches).
fn check_cell(
    scene: &Scene,
    p: DVec3,
    front: Option<DVec3>,
    region: (DVec3, DVec3),
    cell: (DVec3, DVec3),
    rng: &mut Philox4x32,
    mism: &mut Vec<String>,
) -> (usize, usize) {
    let occ = scene.occluders(p, front, Some(region));
    let mask = scene.cell_visibility(p, &occ, cell);
    let ip = scene.inside_mask(p);
    let mut pairs = 0;
    for x in points(rng, cell) {
        if front.is_some_and(|n| n.dot(x - p) <= 0.0) {
            continue;
        }
        // Only points within the region (the lists' guarantee), up to the
        // ulps of the lookup.
        let inside = scene.inside_mask(x) & ip;
        let want = scene.blocked_by_shapes(x, None, p, inside);
        let l2 = (x - p).length_squared();
        let full = scene.blocked_by_occluders(x, None, p, inside, &occ, l2);
        let got = scene.blocked_in_cell(x, None, p, inside, &occ, mask, l2);
        pairs += 1;
        if got != want || full != want {
            let kind = if full == want {
                "CELL-ONLY"
            } else if got == full {
                "LIST-TOO"
            } else {
                "BOTH-DIFFER"
            };
            mism.push(format!(
                "{kind} p {p:?} front {front:?} x {x:?} cell {cell:?} mask {mask:x}: cell {got}, list {full}, full {want}"
            ));
        }
    }
    (pairs, (mask == CELL_DARK) as usize)
}

/// Print one offset's mismatches by kind, and the first.
fn report_offset(o: DVec3, mism: &[String]) {
    let kinds = |k: &str| mism.iter().filter(|m| m.starts_with(k)).count();
    let dark_wrong = mism.iter().filter(|m| m.contains("cell true")).count();
    eprintln!(
        "offset {o}: {} mismatches ({} cell only, {} list too, {} cell says blocked)",
        mism.len(),
        kinds("CELL-ONLY"),
        kinds("LIST-TOO"),
        dark_wrong
    );
    if let Some(m) = mism.first() {
        eprintln!("  first: {m}");
    }
}

/// Print the totals and the first mismatches.
fn report_total(pairs: usize, dark: usize, mism: &[String]) {
    eprintln!(
        "{pairs} pairs, {dark} dark cells, {} mismatches",
        mism.len()
    );
    for m in mism.iter().take(10) {
        eprintln!("{m}");
    }
}

/// A tilted rectangle, a small box, a tilted disc, far from the origin
/// (offset `o`), plus a light.
fn far_scene(o: DVec3, name: &str) -> Scene {
    let f = |v: DVec3| format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z);
    scene_from(
        name,
        &format!(
            r#"
[[surface]]
type = "rectangle"
corner = {}
edge1 = [0.013, 0.0031, 0.0017]
edge2 = [-0.0021, 0.011, 0.0029]
sides = "both"
material = {{ type = "lambertian", reflectance = 0.5 }}

[[surface]]
type = "box"
min = {}
max = {}
normals = "outward"
material = {{ type = "lambertian", reflectance = 0.5 }}

[[surface]]
type = "disc"
center = {}
normal = [0.3, -0.5, 1]
radius = 0.007
sides = "both"
material = {{ type = "lambertian", reflectance = 0.5 }}

[[light]]
type = "point"
position = {}
intensity = 100
"#,
            f(o),
            f(o + DVec3::new(0.1, 0.0, 0.0)),
            f(o + DVec3::new(0.1 + 3e-4, 2e-4, 5e-4)),
            f(o + DVec3::new(0.0, 0.1, 0.0)),
            f(o + DVec3::new(0.0, 0.0, 5.0)),
        ),
    )
}

/// Cells in the beam behind a shape from `p`, at random depths and sizes
/// (many of them proved dark), grazing ones (receiver within 1e-6..1e-3
/// of the rectangle's plane) when `grazing`; the mismatches.
fn behind_small_shapes(offsets: &[DVec3], grazing: bool) -> Vec<String> {
    let mut mism = Vec::new();
    let (mut pairs, mut dark) = (0, 0);
    let mut rng = Philox4x32::new(77, 0);
    for (si, &o) in offsets.iter().enumerate() {
        let scene = far_scene(o, &format!("far{si}-{}-{grazing}", o.x));
        let before = mism.len();
        // Targets: the rectangle, the box, the disc.
        let rect_o = o;
        let (e1, e2) = (
            DVec3::new(0.013, 0.0031, 0.0017),
            DVec3::new(-0.0021, 0.011, 0.0029),
        );
        let n = e1.cross(e2).normalize();
        let bx = (
            o + DVec3::new(0.1, 0.0, 0.0),
            o + DVec3::new(0.1 + 3e-4, 2e-4, 5e-4),
        );
        for it in 0..6000 {
            let (u, v, w) = (rng.next_2d(), rng.next_2d(), rng.next_2d());
            let target = it % 2;
            // A point of the shape (near its edges often).
            let edge = |a: f64| {
                if a < 0.3 {
                    a * 1e-5
                } else if a > 0.7 {
                    1.0 - (1.0 - a) * 1e-5
                } else {
                    a
                }
            };
            let y = if target == 0 {
                rect_o + e1 * edge(u[0]) + e2 * edge(u[1])
            } else {
                bx.0 + (bx.1 - bx.0) * DVec3::new(edge(u[0]), edge(u[1]), edge(v[0]))
            };
            // The receiver: from near the plane (grazing) to far.
            let dir = DVec3::new(v[1] - 0.5, w[0] - 0.5, w[1] - 0.5).normalize_or_zero();
            let dist = 10f64.powf(-3.0 + 4.0 * rng.next_2d()[0]);
            let mut p = y + dir * dist;
            if grazing && target == 0 && it % 3 == 0 {
                // Grazing: the receiver barely off the rectangle's plane.
                let h = 10f64.powf(-6.0 + 3.0 * rng.next_2d()[0]) * (1.0 + o.abs().max_element());
                let lat = (dir - n * n.dot(dir)).normalize_or_zero();
                p = y + lat * dist + n * h;
            }
            // The cell: round a point beyond the shape on the same line.
            let t = 1.0 + 10f64.powf(-4.0 + 4.0 * rng.next_2d()[0]);
            let c = p + (y - p) * t;
            let s = 10f64.powf(-8.0 + 6.0 * rng.next_2d()[0]) * (1.0 + (c - p).length());
            let r = rng.next_2d();
            let half = DVec3::new(s, s * (0.1 + r[0]), s * (0.1 + r[1]));
            let cell = (c - half, c + half);
            let region = (cell.0 - half * 3.0, cell.1 + half * 3.0);
            let (k, d) = check_cell(&scene, p, None, region, cell, &mut rng, &mut mism);
            pairs += k;
            dark += d;
        }
        report_offset(o, &mism[before..]);
    }
    report_total(pairs, dark, &mism);
    assert!(dark > 500, "{dark}");
    mism
}

const OFFSETS: [DVec3; 3] = [
    DVec3::ZERO,
    DVec3::new(1e3, -2e3, 7e2),
    DVec3::new(3e4, 1e4, -2e4),
];

/// Small shapes near the origin and far from it, no grazing receivers:
/// cells, lists and the full test agree everywhere.
#[test]
fn cells_behind_small_far_shapes_agree_with_the_full_test() {
    let mism = behind_small_shapes(&OFFSETS, false);
    assert!(mism.is_empty(), "{} mismatches", mism.len());
}

/// Receivers within 1e-6..1e-3 m of a 1.3 cm tilted rectangle's plane, a
/// few metres away: the occluder list's pyramid test (its planes through
/// the receiver and the grown edges are computed from nearly parallel
/// vectors) ruled the rectangle out for segments its own test finds
/// crossing it (`list false, full true`), a hole of the occluder lists
/// that the review found; the pyramid is now dropped for receivers that
/// close to the plane (`rect_pyramid`), and this must agree.
#[test]
fn grazing_receivers_agree_with_the_full_test() {
    let mism = behind_small_shapes(&OFFSETS[..1], true);
    assert!(mism.iter().all(|m| !m.starts_with("CELL-ONLY")));
    assert!(mism.is_empty(), "{} mismatches", mism.len());
}

/// Receivers exactly on a box's face planes (on the face and beside it),
/// and cells on or just off that plane; the mismatches.
fn on_box_face_planes(offsets: &[DVec3]) -> Vec<String> {
    let mut mism = Vec::new();
    let (mut pairs, mut dark) = (0, 0);
    let mut rng = Philox4x32::new(78, 0);
    for (si, &o) in offsets.iter().enumerate() {
        let scene = far_scene(o, &format!("face{si}-{}", o.x));
        let before = mism.len();
        let (lo, hi) = (
            o + DVec3::new(0.1, 0.0, 0.0),
            o + DVec3::new(0.1 + 3e-4, 2e-4, 5e-4),
        );
        let ext = hi - lo;
        let tol = 1e-10 * ext.max_element();
        for it in 0..6000 {
            let (u, v, w) = (rng.next_2d(), rng.next_2d(), rng.next_2d());
            let a = it % 3;
            let top = it % 2 == 0;
            let plane = if top { hi[a] } else { lo[a] };
            let sgn = if top { 1.0 } else { -1.0 };
            // The receiver on the face plane: on the face or beside it.
            let spread = if it % 4 < 2 { 1.0 } else { 3.0 };
            let mut p = lo
                + ext
                    * DVec3::new(
                        (u[0] - 0.5) * spread + 0.5,
                        (u[1] - 0.5) * spread + 0.5,
                        (v[0] - 0.5) * spread + 0.5,
                    );
            p[a] = plane;
            // The cell: on the plane's outer side, its inner face within a
            // few tolerances of the plane (inside the band or out of it).
            let off = (v[1] - 0.3) * 2.0 * tol;
            let size = ext.max_element() * 10f64.powf(-3.0 + 3.5 * w[0]);
            let centre = lo
                + ext
                    * DVec3::new(
                        (w[1] - 0.5) * 4.0 + 0.5,
                        (u[0] - 0.5) * 4.0 + 0.5,
                        (u[1] - 0.5) * 4.0 + 0.5,
                    );
            let mut clo = centre - DVec3::splat(size);
            let mut chi = centre + DVec3::splat(size);
            if top {
                clo[a] = plane - off;
                chi[a] = clo[a] + size;
            } else {
                chi[a] = plane + off;
                clo[a] = chi[a] - size;
            }
            let cell = (clo, chi);
            let region = (clo - DVec3::splat(size), chi + DVec3::splat(size));
            let mut front = None;
            if it % 5 != 0 {
                let mut n = DVec3::ZERO;
                n[a] = sgn;
                front = Some(n);
            }
            let (k, d) = check_cell(&scene, p, front, region, cell, &mut rng, &mut mism);
            pairs += k;
            dark += d;
        }
        report_offset(o, &mism[before..]);
    }
    report_total(pairs, dark, &mism);
    mism
}

/// A small box (0.3 x 0.2 x 0.5 mm) near the origin: cells and lists
/// agree with the full test for receivers on its face planes.
#[test]
fn cells_on_box_face_planes_agree_with_the_full_test() {
    let mism = on_box_face_planes(&OFFSETS[..1]);
    assert!(mism.is_empty(), "{} mismatches", mism.len());
}

/// The same box 1e3 and 3e4 m from the origin: 1e-10 of 0.5 mm is below
/// half an ulp of its coordinates, so with that tolerance its test's
/// shrunk box was the box itself and segments along a face plane (a
/// receiver on the face) counted as crossing it, while the lists
/// (exact-face separating plane) and the cells (`box_face_holds_cell`)
/// drop the box there (found by the review). The box tolerance now has a
/// floor of 64 ulps of its coordinates, and this must agree.
#[test]
fn cells_on_far_tiny_box_face_planes_agree_with_the_full_test() {
    let mism = on_box_face_planes(&OFFSETS[1..]);
    assert!(mism.is_empty(), "{} mismatches", mism.len());
}

/// Cells proved dark by a small tilted rectangle from a receiver barely
/// beyond the proof's margin off its plane (grazing segments): the
/// rounding of the crossing points is largest there.
#[test]
fn grazing_dark_cells_behind_a_rectangle_agree_with_the_full_test() {
    let mut mism = Vec::new();
    let (mut pairs, mut dark) = (0, 0);
    let mut rng = Philox4x32::new(79, 0);
    let scene = far_scene(DVec3::ZERO, "grazing");
    let (e1, e2) = (
        DVec3::new(0.013, 0.0031, 0.0017),
        DVec3::new(-0.0021, 0.011, 0.0029),
    );
    let n = e1.cross(e2).normalize();
    for _ in 0..20000 {
        let (u, v, w) = (rng.next_2d(), rng.next_2d(), rng.next_2d());
        let edge = |a: f64| {
            if a < 0.25 {
                1.5e-7 + a * 1e-5
            } else if a > 0.75 {
                1.0 - 1.5e-7 - (1.0 - a) * 1e-5
            } else {
                a
            }
        };
        let y = e1 * edge(u[0]) + e2 * edge(u[1]);
        let dir = DVec3::new(v[0] - 0.5, v[1] - 0.5, w[0] - 0.5);
        let lat = (dir - n * n.dot(dir)).normalize_or_zero();
        let l = 0.5 + 9.5 * w[1];
        let scale = l + 0.02;
        let m = 1e-7 * scale;
        let r = rng.next_2d();
        let h = m * (1.3 + 20.0 * r[0] * r[0]);
        let sgn = if r[1] < 0.5 { 1.0 } else { -1.0 };
        let p = y + lat * l + n * (h * sgn);
        // (At most `h`: the cell no farther from the origin than `p`.)
        let depth = m * 1.2 + (h - m * 1.2) * rng.next_2d()[0];
        let c = p + (y - p) * (1.0 + depth / h);
        let s = 10f64.powf(-16.0 + 5.0 * rng.next_2d()[0]);
        let cell = (c - DVec3::splat(s), c + DVec3::splat(s));
        let region = (cell.0 - DVec3::splat(s), cell.1 + DVec3::splat(s));
        let (k, d) = check_cell(&scene, p, None, region, cell, &mut rng, &mut mism);
        pairs += k;
        dark += d;
    }
    let dark_wrong = mism.iter().filter(|m| m.contains("cell true")).count();
    let cell_only = mism.iter().filter(|m| m.starts_with("CELL-ONLY")).count();
    eprintln!(
        "{cell_only} cell only; {pairs} pairs, {dark} dark cells, {} mismatches ({dark_wrong} cell says blocked)",
        mism.len()
    );
    for m in mism.iter().take(5) {
        eprintln!("{m}");
    }
    assert!(dark > 1000, "{dark}");
    // No dark cell is wrong, and the cells give the list's answer (the
    // list's own answers at grazing receivers: the test above).
    assert_eq!(dark_wrong, 0);
    assert_eq!(cell_only, 0);
}
