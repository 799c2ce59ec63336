//! Points inside a solid, behind a wall or outside a closed room are
//! flagged `enclosed` and left out of the grid figures; a light sealed
//! inside a solid is warned about.

mod common;

use glam::DVec3;
use lumest::commands::illuminance::grid_summary;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::scene::parse;
use std::path::Path;

const ROOM: &str = r#"
[[surface]]
name = "room"
type = "box"
min = [0.0, 0.0, 0.0]
max = [4.0, 3.0, 3.0]
normals = "inward"
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
name = "desk"
type = "box"
min = [1.0, 1.0, 0.0]
max = [2.0, 2.0, 0.75]
normals = "outward"
material = { type = "lambertian", reflectance = 0.6 }
"#;

#[test]
fn points_in_solids_behind_walls_and_outside_the_room_are_flagged_and_left_out() {
    let scene = parse(
        &format!(
            "{ROOM}[[light]]\ntype = \"point\"\nposition = [3.0, 1.5, 2.5]\nintensity = 200.0\n"
        ),
        Path::new("room.toml"),
    )
    .unwrap();
    assert!(scene.notes.is_empty(), "{:?}", scene.notes);
    let points = [
        (DVec3::new(3.0, 0.5, 0.0), DVec3::Z),  // on the floor: fine
        (DVec3::new(1.5, 1.5, 0.75), DVec3::Z), // on the desk top: fine
        (DVec3::new(0.5, 2.5, 1.0), DVec3::X),  // facing into the room from a wall: fine
        (DVec3::new(1.5, 1.5, 0.4), DVec3::Z),  // inside the desk
        (DVec3::new(2.0, 1.5, 3.5), -DVec3::Z), // above the ceiling, facing it
        (DVec3::new(5.0, 1.5, 1.0), -DVec3::X), // outside the room, facing its wall
    ];
    let rec = Receivers::new(&scene, &points).unwrap();
    let enclosed: Vec<bool> = (0..points.len()).map(|j| rec.enclosed(j)).collect();
    assert_eq!(enclosed, [false, false, false, true, true, true]);
    let r = run(&scene, &rec, &common::chains_cfg(20_000, 1, 2), &mut |_| {
        true
    });
    for (j, &e) in enclosed.iter().enumerate() {
        let flag = r.tallies.diagnostics(j, r.direct[j]).flag();
        assert_eq!(flag.contains("enclosed"), e, "point {j}: {flag}");
    }
    // The figures use the three good points only, and say so.
    let line = grid_summary(&r, points.len()).unwrap();
    assert!(line.contains("3 of 6 point(s) left out"), "{line}");
    let e: Vec<f64> = (0..3)
        .map(|j| r.direct[j] + r.tallies.estimated[j].mean())
        .collect();
    let min = e.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(min > 0.0);
    assert!(line.contains(&format!("E_min {min:.4} lx")), "{line}");
}

#[test]
fn a_light_sealed_inside_a_solid_is_warned_about() {
    let sealed = parse(
        &format!(
            "{ROOM}[[light]]\ntype = \"point\"\nposition = [1.5, 1.5, 0.4]\nintensity = 200.0\n"
        ),
        Path::new("room.toml"),
    )
    .unwrap();
    assert!(sealed.sealed(0));
    assert!(
        sealed
            .notes
            .iter()
            .any(|n| n.contains("WARNING") && n.contains("sealed")),
        "{:?}",
        sealed.notes
    );
    let free = parse(
        &format!(
            "{ROOM}[[light]]\ntype = \"point\"\nposition = [1.5, 1.5, 0.9]\nintensity = 200.0\n"
        ),
        Path::new("room.toml"),
    )
    .unwrap();
    assert!(!free.sealed(0));
}

/// The box `[lo, hi]` \[m\] as OBJ text: a closed mesh with outward,
/// counter-clockwise faces.
fn box_obj(lo: DVec3, hi: DVec3) -> String {
    let mut obj = String::new();
    for k in 0..8 {
        let c = DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, ((k >> 2) & 1) as f64);
        let v = lo + c * (hi - lo);
        obj += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    // (1-based.)
    for f in [
        [1, 3, 2],
        [2, 3, 4],
        [5, 6, 7],
        [6, 8, 7],
        [1, 2, 5],
        [2, 6, 5],
        [3, 7, 4],
        [4, 7, 8],
        [1, 5, 3],
        [3, 5, 7],
        [2, 4, 6],
        [4, 8, 6],
    ] {
        obj += &format!("f {} {} {}\n", f[0], f[1], f[2]);
    }
    obj
}

/// A desk as a closed mesh (the unit cube scaled to 1 x 1 x 0.75 m, both
/// sides reflecting, the mesh default), in the room with `light`; the
/// scene file and its OBJ in a fresh folder.
fn mesh_desk_room(light: [f64; 3], tag: &str) -> lumest::scene::Scene {
    let dir = std::env::temp_dir().join(format!("lumest-enclosed-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let obj = box_obj(DVec3::new(1.0, 1.0, 0.0), DVec3::new(2.0, 2.0, 0.75));
    std::fs::write(dir.join("desk.obj"), obj).unwrap();
    let room = ROOM.split("[[surface]]\nname = \"desk\"").next().unwrap();
    let toml = format!(
        "{room}[[surface]]\nname = \"desk\"\ntype = \"mesh\"\nfile = \"desk.obj\"\n\
         material = {{ type = \"lambertian\", reflectance = 0.6 }}\n\n\
         [[light]]\ntype = \"point\"\nposition = {light:?}\nintensity = 200.0\n"
    );
    let path = dir.join("room.toml");
    std::fs::write(&path, &toml).unwrap();
    let scene = lumest::scene::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    scene
}

/// A point inside a closed mesh whose both sides reflect sees no black
/// side, yet no light can reach it: it is flagged `enclosed` (it read
/// E = 0, flag `ok`). Points on the mesh's top and outside it are not; and
/// with the light inside the mesh, the point inside is lit and not flagged.
#[test]
fn a_point_inside_a_closed_two_sided_mesh_is_enclosed_unless_a_light_is_inside() {
    let points = [
        (DVec3::new(1.5, 1.5, 0.4), DVec3::Z),  // inside the desk
        (DVec3::new(1.5, 1.5, 0.75), DVec3::Z), // on its top
        (DVec3::new(3.0, 0.5, 0.0), DVec3::Z),  // on the floor
        (DVec3::new(1.5, 1.5, 0.4), DVec3::X),  // inside, facing sideways
        (DVec3::new(2.2, 1.5, 0.4), -DVec3::X), // 20 cm off its side, facing it
    ];
    let want = [true, false, false, true, false];
    let scene = mesh_desk_room([3.0, 1.5, 2.5], "out");
    let rec = Receivers::new(&scene, &points).unwrap();
    let enclosed: Vec<bool> = (0..points.len()).map(|j| rec.enclosed(j)).collect();
    assert_eq!(enclosed, want);
    let r = run(&scene, &rec, &common::chains_cfg(20_000, 1, 2), &mut |_| {
        true
    });
    for (j, &e) in want.iter().enumerate() {
        let flag = r.tallies.diagnostics(j, r.direct[j]).flag();
        assert_eq!(flag.contains("enclosed"), e, "point {j}: {flag}");
        let lit = r.direct[j] + r.tallies.estimated[j].mean();
        assert_eq!(lit > 0.0, !e, "point {j}: E {lit}");
    }
    // The same desk with the light inside it: the inside point is lit.
    let lit = mesh_desk_room([1.5, 1.5, 0.6], "in");
    let rec = Receivers::new(&lit, &points[..1]).unwrap();
    assert!(!rec.enclosed(0));
    assert!(rec.direct()[0] > 0.0);
    // A lamp standing on the desk's side stands outside it (its seat's
    // side): the inside still holds no light (it read 0, flagged `ok`: a
    // light on the mesh counted as held; a reviewer's find).
    let on_side = mesh_desk_room([2.0, 1.3, 0.5], "side");
    assert!(on_side.light_surface(0).is_some());
    let rec = Receivers::new(&on_side, &points).unwrap();
    let enclosed: Vec<bool> = (0..points.len()).map(|j| rec.enclosed(j)).collect();
    assert_eq!(enclosed, want);
}

/// A room that is itself a closed mesh (a 4 x 3 x 3 m box, both sides
/// reflecting) lit by a sphere light whose centre lies 2 cm above the
/// ceiling and whose ball reaches 3 cm below it (a reviewer's case): the
/// light is partly inside, so the room holds light and its points are not
/// enclosed (a rule that looked at the centre alone flagged a point lit at
/// 48.7 lx). With a point light above the ceiling instead, no light gets
/// in: the point is enclosed, and indeed unlit.
#[test]
fn a_light_partly_inside_a_closed_mesh_lights_it() {
    let go = |light: &str, tag: &str| {
        let dir =
            std::env::temp_dir().join(format!("lumest-enclosed-{}-{tag}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = box_obj(DVec3::ZERO, DVec3::new(4.0, 3.0, 3.0));
        std::fs::write(dir.join("room.obj"), obj).unwrap();
        let toml = format!(
            "[[surface]]\nname = \"room\"\ntype = \"mesh\"\nfile = \"room.obj\"\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\n[[light]]\n{light}"
        );
        let path = dir.join("room.toml");
        std::fs::write(&path, &toml).unwrap();
        let scene = lumest::scene::load(&path).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let pts = [(DVec3::new(2.0, 1.5, 0.8), DVec3::Z)];
        let rec = Receivers::new(&scene, &pts).unwrap();
        let r = run(&scene, &rec, &common::chains_cfg(8_192, 1, 2), &mut |_| {
            true
        });
        (rec.enclosed(0), r.direct[0] + r.tallies.estimated[0].mean())
    };
    let (enclosed, e) = go(
        "type = \"sphere\"\ncenter = [2.0, 1.5, 3.02]\nradius = 0.05\nintensity = 100.0\n",
        "sphere",
    );
    assert!(
        !enclosed && e > 1.0,
        "sphere light poking in: enclosed {enclosed}, E {e}"
    );
    let (enclosed, e) = go(
        "type = \"point\"\nposition = [2.0, 1.5, 3.5]\nintensity = 100.0\n",
        "point",
    );
    assert!(
        enclosed && e == 0.0,
        "point light above: enclosed {enclosed}, E {e}"
    );
}

/// A point on a room's boundary with its normal out of the room (the
/// floor's facing down, a wall's facing out, the ceiling's facing up), or
/// on a solid facing into it, or on a plane facing its black side, where
/// no light is on that side, is enclosed: its probes leave the surface and
/// meet nothing, so it read 0 lx flagged `ok` and a grid holding one
/// reported U0 = 0, "not met". A point on a one-sided rectangle's black
/// side (under a shelf) or on a sphere whose two sides reflect is not.
#[test]
fn points_on_a_surface_facing_its_black_side_are_flagged() {
    let scene = parse(
        &format!(
            "{ROOM}[[surface]]\nname = \"shelf\"\ntype = \"rectangle\"\ncorner = [3, 0.5, 1.5]\n\
             edge1 = [0.5, 0, 0]\nedge2 = [0, 0.5, 0]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[surface]]\nname = \"bubble\"\ntype = \"sphere\"\ncenter = [2.7, 2.2, 0.5]\nradius = 0.2\n\
             sides = \"both\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[surface]]\nname = \"ball\"\ntype = \"sphere\"\ncenter = [0.5, 0.5, 2.5]\nradius = 0.2\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[surface]]\nname = \"outer\"\ntype = \"plane\"\npoint = [0, 0, -1]\nnormal = [0, 0, 1]\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[light]]\ntype = \"point\"\nposition = [3.0, 1.5, 2.5]\nintensity = 200.0\n"
        ),
        Path::new("room.toml"),
    )
    .unwrap();
    let points = [
        (DVec3::new(3.0, 0.5, 0.0), -DVec3::Z),  // floor, facing down
        (DVec3::new(0.0, 2.0, 1.5), -DVec3::X),  // wall, facing out
        (DVec3::new(3.0, 2.0, 3.0), DVec3::Z),   // ceiling, facing up
        (DVec3::new(1.5, 1.5, 0.75), -DVec3::Z), // desk top, facing in
        (DVec3::new(0.5, 0.5, 2.3), DVec3::Z),   // ball's bottom, facing in
        (DVec3::new(1.0, 1.0, -1.0), -DVec3::Z), // plane's black side, no light
        (DVec3::new(3.0, 0.5, 0.0), DVec3::Z),   // floor, facing up: fine
        (DVec3::new(3.2, 0.7, 1.5), -DVec3::Z),  // under the shelf: fine
        (DVec3::new(2.7, 2.2, 0.7), -DVec3::Z),  // both-sided bubble's top, in: fine
        (DVec3::new(0.0, 2.0, 1.5), DVec3::X),   // wall, facing in: fine
    ];
    let rec = Receivers::new(&scene, &points).unwrap();
    let enclosed: Vec<bool> = (0..points.len()).map(|j| rec.enclosed(j)).collect();
    assert_eq!(
        enclosed,
        [
            true, true, true, true, true, true, false, false, false, false
        ]
    );
}

/// ... and points that do get light are not flagged: a facade point facing
/// out under the sun, a point on a wall two rooms share (facing the other
/// room), the floor along a cabinet's foot (its bottom face's black side),
/// a point on a plane's black side with a light there; but the floor under
/// the cabinet is inside it (it read 0 lx, ok: half its probes met the
/// walls the cabinet stands against).
#[test]
fn points_on_a_black_side_that_light_reaches_are_not_flagged() {
    let lamb = "material = { type = \"lambertian\", reflectance = 0.5 }";
    let scene = parse(
        &format!(
            "[[surface]]\nname = \"a\"\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [6, 4, 3]\n{lamb}\n\
             [[surface]]\nname = \"b\"\ntype = \"box\"\nmin = [6, 0, 0]\nmax = [10, 4, 3]\n{lamb}\n\
             [[surface]]\nname = \"cabinet\"\ntype = \"box\"\nmin = [0, 0, 0]\nmax = [1, 0.6, 1.2]\n\
             normals = \"outward\"\n{lamb}\n\
             [[surface]]\nname = \"under\"\ntype = \"plane\"\npoint = [0, 0, -2]\nnormal = [0, 0, -1]\n{lamb}\n\
             [[light]]\ntype = \"point\"\nposition = [3, 2, 2.5]\nintensity = 100\n\
             [[light]]\ntype = \"point\"\nposition = [8, 2, 2.5]\nintensity = 100\n\
             [[light]]\ntype = \"distant\"\ndirection = [-0.6, 0.3, -0.7]\nilluminance = 1000\n"
        ),
        Path::new("rooms.toml"),
    )
    .unwrap();
    let points = [
        (DVec3::new(0.0, 2.0, 1.5), -DVec3::X), // facade, under the sun
        (DVec3::new(3.0, 2.0, 3.0), DVec3::Z),  // roof, under the sun
        (DVec3::new(6.0, 2.0, 1.5), -DVec3::X), // shared wall, into room a
        (DVec3::new(6.0, 2.0, 1.5), DVec3::X),  // shared wall, into room b
        (DVec3::new(1.0, 0.3, 0.0), DVec3::Z),  // floor at the cabinet's foot
        (DVec3::new(1.0, 0.6, 0.0), DVec3::Z),  // ... at its corner
        (DVec3::new(20.0, 20.0, -2.0), DVec3::Z), // plane's black side, lights there
        (DVec3::new(0.5, 0.3, 1.2), -DVec3::Z), // cabinet top facing in: enclosed
        (DVec3::new(0.5, 0.3, 0.0), DVec3::Z),  // floor under the cabinet: enclosed
    ];
    let rec = Receivers::new(&scene, &points).unwrap();
    let enclosed: Vec<bool> = (0..points.len()).map(|j| rec.enclosed(j)).collect();
    assert_eq!(
        enclosed,
        [false, false, false, false, false, false, false, true, true]
    );
}
