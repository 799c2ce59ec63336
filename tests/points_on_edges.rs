//! A receiver lying on a surface it does not face along (a floor point at
//! a wall's foot facing up, a room's corner point facing its diagonal, a
//! floor point facing along the floor) reads the limit from the side it
//! faces (`Scene::lift_to_its_side`). Evaluated on the surface itself it
//! saw that surface edge-on and counted none of its light: 35.26 lx
//! against 41.88 a micrometre into the room, flagged `ok`, in boxes,
//! rectangles and meshes alike (a reviewer's find).
//!
//! A point edge-on to a face of a closed two-sided mesh (a room or a
//! cabinet as an OBJ, `sides = "both"`) belongs to the side the light is
//! on.
//!
//! Reference: the same points a micrometre into the room (the value
//! varies by some 1e-6 of itself over that distance), with another seed;
//! for the rooms built of rectangles and of meshes, the box room's.

mod common;

use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::scene::{Scene, parse};
use lumest::tally::sidak_bound;

const LIGHT: &str = r#"
[[light]]
type = "point"
position = [0.5, 0.5, 2.0]
intensity = 100
"#;

const BOX_ROOM: &str = r#"
[[surface]]
type = "box"
min = [0, 0, 0]
max = [4, 3, 2.5]
normals = "inward"
material = { type = "lambertian", reflectance = 0.5 }
"#;

const CABINET: &str = r#"
[[surface]]
type = "box"
min = [1, 1, 0]
max = [2, 2, 1]
normals = "outward"
material = { type = "lambertian", reflectance = 0.8 }
"#;

/// The room as one mesh, counter-clockwise seen from inside.
const ROOM_OBJ: &str = "v 0 0 0\nv 4 0 0\nv 0 3 0\nv 4 3 0\nv 0 0 2.5\nv 4 0 2.5\nv 0 3 2.5\nv 4 3 2.5\n\
f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\nf 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n";

/// The box `[1, 2]^2 x [0, 1]` (a cabinet, with its bottom) as one mesh,
/// counter-clockwise seen from inside.
const CABINET_OBJ: &str = "v 1 1 0\nv 2 1 0\nv 1 2 0\nv 2 2 0\nv 1 1 1\nv 2 1 1\nv 1 2 1\nv 2 2 1\n\
f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\nf 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n";

fn scene(text: &str, dir: &std::path::Path) -> Scene {
    parse(&format!("{text}{LIGHT}"), &dir.join("room.toml")).unwrap()
}

/// `(E, standard error, flag)` at each point \[lx\].
fn illuminance(scene: &Scene, points: &[(DVec3, DVec3)], seed: u64) -> Vec<(f64, f64, String)> {
    let rec = Receivers::new(scene, points).unwrap();
    let r = lumest::estimator::local::run(
        scene,
        &rec,
        &common::chains_cfg(200_000, seed, 2),
        &mut |_| true,
    );
    (0..points.len())
        .map(|j| {
            let t = &r.tallies.estimated[j];
            let flag = r.tallies.diagnostics(j, r.direct[j]).flag();
            (r.direct[j] + t.mean(), t.std_error(), flag)
        })
        .collect()
}

/// Check `got` against `want` point by point; `bound` the z bound; every
/// row `ok`.
fn agree(what: &str, got: &[(f64, f64, String)], want: &[(f64, f64, String)], bound: f64) {
    agree_flagged(what, got, want, bound, "ok", &[]);
}

/// [`agree`] at the five points `on` of the rooms (or their neighbours
/// off the surfaces), rows 2 and 3 `ok` or `sparse` (see
/// [`agree_flagged`]).
fn agree_on(what: &str, got: &[(f64, f64, String)], want: &[(f64, f64, String)], bound: f64) {
    agree_flagged(what, got, want, bound, "ok", &[2, 3]);
}

/// [`agree`], every row carrying the flag `expected`, or `sparse` at the
/// rows `sparse_rows` (see below for why).
fn agree_flagged(
    what: &str,
    got: &[(f64, f64, String)],
    want: &[(f64, f64, String)],
    bound: f64,
    expected: &str,
    sparse_rows: &[usize],
) {
    for (j, (g, w)) in got.iter().zip(want).enumerate() {
        let se = g.1.hypot(w.1);
        // Precise enough that a 2 % error shows.
        assert!(0.02 * w.0 > bound * se, "{what} {j}: se {se} on {}", w.0);
        let z = (g.0 - w.0) / se;
        assert!(z.abs() < bound, "{what} {j}: {g:?} against {w:?}, z = {z}");
        // `sparse` is the flag two kinds of rows may carry, on the surface
        // and a micrometre off alike. A point facing along a surface (the
        // floor point facing along the floor, a point on a cabinet's side
        // facing up) reads half its light from the surface within
        // micrometres of it, which few of a short run's samples reach. And
        // the wall's foot far from the light (row 2 of the rooms): its near
        // part's paths come within reach of the light's core in a few runs
        // only, and then fewer than 10 times (`Diagnostics::near_reach`):
        // 4 of 30 seeds in the box room flag it, in this build and the one
        // before (the seeds here once all missed it).
        let allowed = |f: &str| f == expected || (sparse_rows.contains(&j) && f == "sparse");
        assert!(
            allowed(&g.2) && allowed(&w.2),
            "{what} {j}: {} / {}",
            g.2,
            w.2
        );
    }
}

#[test]
fn points_on_edges_and_corners_read_the_limit_from_their_side() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("room.obj"), ROOM_OBJ).unwrap();
    let d = DVec3::new;
    let diag = d(1.0, 1.0, 1.0).normalize();
    // On the floor at the wall's foot facing up, in the corner facing its
    // diagonal, at the wall's foot facing up further along, on the floor
    // facing along it, on a wall facing up; each a micrometre into the room.
    let on = [
        (d(0.0, 1.5, 0.0), DVec3::Z),
        (d(0.0, 0.0, 0.0), diag),
        (d(3.0, 3.0, 0.0), DVec3::Z),
        (d(2.5, 0.5, 0.0), DVec3::X),
        (d(2.5, 0.0, 1.2), DVec3::Z),
    ];
    let off: Vec<(DVec3, DVec3)> = [
        d(1e-6, 0.0, 1e-6),
        d(1e-6, 1e-6, 1e-6),
        d(0.0, -1e-6, 1e-6),
        d(0.0, 0.0, 1e-6),
        d(0.0, 1e-6, 0.0),
    ]
    .iter()
    .zip(&on)
    .map(|(&o, &(p, n))| (p + o, n))
    .collect();
    // Five rooms at each point, then twenty-one more pairs.
    let bound = sidak_bound(1e-3, 5 * on.len() + 21, None);
    let boxed = scene(BOX_ROOM, dir.path());
    let want = illuminance(&boxed, &off, 11);
    agree_on("box room", &illuminance(&boxed, &on, 12), &want, bound);
    let rects = scene(
        &common::rectangle_room([4.0, 3.0, 2.5], [0.5; 6]),
        dir.path(),
    );
    agree_on("rectangles", &illuminance(&rects, &on, 13), &want, bound);
    let mesh = scene(
        "[[surface]]\ntype = \"mesh\"\nfile = \"room.obj\"\nsides = \"front\"\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n",
        dir.path(),
    );
    agree_on("mesh room", &illuminance(&mesh, &on, 14), &want, bound);
    // The same closed mesh reflecting on both sides (the default), wound
    // either way: a point edge-on to a wall belongs to the side the light
    // is on. It saw past the wall on both sides, as past a sheet, and
    // counted the dark outside: 33.56 against 39.22 lx at a wall's foot.
    for (name, obj) in [
        ("in.obj", ROOM_OBJ.to_string()),
        ("out.obj", common::rewound_obj(ROOM_OBJ)),
    ] {
        std::fs::write(dir.path().join(name), obj).unwrap();
        let mesh = scene(
            &format!(
                "[[surface]]\ntype = \"mesh\"\nfile = \"{name}\"\n\
                 material = {{ type = \"lambertian\", reflectance = 0.5 }}\n"
            ),
            dir.path(),
        );
        let what = format!("two-sided mesh room {name}");
        agree_on(&what, &illuminance(&mesh, &on, 14), &want, bound);
    }
    // A cabinet on the floor: a floor point at its foot facing up sees its
    // side over a quarter of the sphere.
    let cab = scene(&format!("{BOX_ROOM}{CABINET}"), dir.path());
    let foot = [(d(1.0, 1.5, 0.0), DVec3::Z)];
    let beside = [(d(1.0 - 1e-6, 1.5, 1e-6), DVec3::Z)];
    agree(
        "cabinet's foot",
        &illuminance(&cab, &foot, 15),
        &illuminance(&cab, &beside, 16),
        bound,
    );
    // At its foot facing along the floor and the cabinet's side: the
    // cabinet's bottom face, lying on the floor facing down, is left out of
    // the move (the two pulled it apart: it stayed on the surface, flagged
    // `enclosed`, 3.22 against 9.29 lx; a reviewer's find).
    let along_foot = [(d(1.5, 1.0, 0.0), DVec3::X)];
    let along_beside = [(d(1.5, 1.0 - 1e-6, 1e-6), DVec3::X)];
    agree_flagged(
        "cabinet's foot, facing along it",
        &illuminance(&cab, &along_foot, 30),
        &illuminance(&cab, &along_beside, 31),
        bound,
        "ok",
        &[0],
    );
    // The same with the room and the cabinet as meshes, reflecting on both
    // sides or on their fronts only (the cabinet wound outward then): the
    // region the move must not enter is the outside of the room mesh,
    // which holds no light (it stayed on the surface and read 2.46
    // against 19.3 lx, flagged `ok`). And at the cabinet's corner where
    // its bottom face's diagonal ends, facing out: two triangles of the
    // bottom, one side (it stayed, 22.96 against 36.73, a reviewer's find).
    let corner_foot = [(d(1.0, 1.0, 0.0), d(-1.0, -1.0, 0.0).normalize())];
    let corner_beside = [(
        d(1.0 - 1e-6, 1.0 - 1e-6, 1e-6),
        d(-1.0, -1.0, 0.0).normalize(),
    )];
    std::fs::write(dir.path().join("cab_in.obj"), CABINET_OBJ).unwrap();
    std::fs::write(
        dir.path().join("cab_out.obj"),
        common::rewound_obj(CABINET_OBJ),
    )
    .unwrap();
    for (what, sides, cab_file) in [
        ("mesh cabinet's foot, both sides", "both", "cab_in.obj"),
        ("mesh cabinet's foot, fronts", "front", "cab_out.obj"),
    ] {
        let meshes = scene(
            &format!(
                "[[surface]]\ntype = \"mesh\"\nfile = \"room.obj\"\nsides = \"{sides}\"\n\
                 material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
                 [[surface]]\ntype = \"mesh\"\nfile = \"{cab_file}\"\nsides = \"{sides}\"\n\
                 material = {{ type = \"lambertian\", reflectance = 0.8 }}\n"
            ),
            dir.path(),
        );
        agree_flagged(
            what,
            &illuminance(&meshes, &along_foot, 32),
            &illuminance(&meshes, &along_beside, 33),
            bound,
            "ok",
            &[0],
        );
        agree(
            &format!("{what}, at its corner"),
            &illuminance(&meshes, &corner_foot, 34),
            &illuminance(&meshes, &corner_beside, 35),
            bound,
        );
    }
    // A cabinet mesh against the room mesh's wall, a downlight exactly on
    // the room mesh's ceiling: at the corner of the floor, the wall and the
    // cabinet's front, facing away from the cabinet, two faces lie against
    // others (the cabinet's bottom on the floor, its side on the wall) and
    // both are left out; the light counts from just off its seat, inside
    // the room. It stayed, 3.29 against 8.99 lx (a reviewer's find).
    std::fs::write(
        dir.path().join("cab_wall.obj"),
        CABINET_OBJ.replace("v 2 ", "v 4 ").replace("v 1 ", "v 3 "),
    )
    .unwrap();
    let wall_cab = parse(
        "[[surface]]\ntype = \"mesh\"\nfile = \"room.obj\"\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[surface]]\ntype = \"mesh\"\nfile = \"cab_wall.obj\"\n\
         material = { type = \"lambertian\", reflectance = 0.8 }\n\
         [[light]]\ntype = \"point\"\nposition = [3.5, 0.5, 2.5]\nintensity = 100\n",
        &dir.path().join("room.toml"),
    )
    .unwrap();
    agree(
        "mesh cabinet against the wall",
        &illuminance(&wall_cab, &[(d(4.0, 1.0, 0.0), -DVec3::Y)], 36),
        &illuminance(
            &wall_cab,
            &[(d(4.0 - 1e-6, 1.0 - 1e-6, 1e-6), -DVec3::Y)],
            37,
        ),
        bound,
    );
    // A mesh cabinet on an infinite ground plane, a lamp above, a point at
    // its lit foot facing along the ground and the cabinet's side: the
    // sides of the ground and the cabinet's bottom cancel, and leaving out
    // either gives a move into a region no solid marks dark (above the
    // ground, or below it); the two lie on different sides of the plane,
    // so the point stays on the surface (under the sun, taking the first
    // move read 0 against 15,156 lx).
    let ground_cab = parse(
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = { type = \"lambertian\", reflectance = 0.3 }\n\
         [[surface]]\ntype = \"mesh\"\nfile = \"cab_in.obj\"\n\
         material = { type = \"lambertian\", reflectance = 0.8 }\n\
         [[light]]\ntype = \"point\"\nposition = [3, 2.5, 2]\nintensity = 100\n",
        &dir.path().join("room.toml"),
    )
    .unwrap();
    agree(
        "mesh cabinet on the ground",
        &illuminance(&ground_cab, &[(d(2.0, 1.5, 0.0), DVec3::Y)], 38),
        &illuminance(&ground_cab, &[(d(2.0 + 1e-6, 1.5, 1e-6), DVec3::Y)], 39),
        bound,
    );
    // A closed two-sided cabinet mesh: a point at its foot and one on its
    // side facing up belong outside it, where the light is.
    std::fs::write(
        dir.path().join("cabinet.obj"),
        common::rewound_obj(CABINET_OBJ),
    )
    .unwrap();
    let cab = scene(
        &format!(
            "{BOX_ROOM}[[surface]]\ntype = \"mesh\"\nfile = \"cabinet.obj\"\n\
             material = {{ type = \"lambertian\", reflectance = 0.8 }}\n"
        ),
        dir.path(),
    );
    let on_cab = [(d(1.0, 1.5, 0.0), DVec3::Z), (d(2.0, 1.5, 0.5), DVec3::Z)];
    let off_cab = [
        (d(1.0 - 1e-6, 1.5, 1e-6), DVec3::Z),
        (d(2.0 + 1e-6, 1.5, 0.5), DVec3::Z),
    ];
    agree(
        "two-sided cabinet mesh",
        &illuminance(&cab, &on_cab, 19),
        &illuminance(&cab, &off_cab, 20),
        bound,
    );
    // The same cabinet modelled in the room's OBJ, both wound outward: its
    // inside lies within two shells, and the points still belong to the
    // room's air, where the light is (they were lifted into the cabinet).
    std::fs::write(
        dir.path().join("both.obj"),
        common::rewound_obj(&format!(
            "{ROOM_OBJ}{}",
            common::shifted_obj(CABINET_OBJ, 8)
        )),
    )
    .unwrap();
    let both = scene(
        "[[surface]]\ntype = \"mesh\"\nfile = \"both.obj\"\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n",
        dir.path(),
    );
    agree(
        "cabinet in the room's mesh",
        &illuminance(&both, &on_cab, 21),
        &illuminance(&both, &off_cab, 22),
        bound,
    );
    // A sun outside the two-sided room mesh as well: a floor point at the
    // foot of a wall the sun's direction leaves through does not see the
    // sun (846 against 16 lx).
    let sunny = scene(
        "[[surface]]\ntype = \"mesh\"\nfile = \"out.obj\"\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"distant\"\ndirection = [-0.5, 0.2, -0.8]\nilluminance = 10\n",
        dir.path(),
    );
    let feet = [(d(4.0, 1.5, 0.0), DVec3::Z), (d(2.0, 0.0, 0.0), DVec3::Z)];
    let inside = [
        (d(4.0 - 1e-6, 1.5, 1e-6), DVec3::Z),
        (d(2.0, 1e-6, 1e-6), DVec3::Z),
    ];
    // The near part runs with a light at infinity too (its paths reach the
    // sun by next-event estimation; they carried `near` before): both
    // points lie at a wall's foot far from the lamp, where `sparse` may
    // mark them (see `agree_flagged`).
    agree_flagged(
        "two-sided room mesh with a sun",
        &illuminance(&sunny, &feet, 23),
        &illuminance(&sunny, &inside, 24),
        bound,
        "ok",
        &[0, 1],
    );
    // A downlight exactly on the box room's ceiling: the points on the
    // floor facing along it and on a wall facing up are lifted and read as
    // with the light 1e-7 m below (they were flagged `enclosed` and read
    // 17.3 against 26.9 lx and 32.9 against 43.8: a light on the box's
    // face counted as in neither region; a reviewer's find).
    let ceiling = |z: f64| {
        parse(
            &format!(
                "{BOX_ROOM}[[light]]\ntype = \"point\"\nposition = [2, 1.5, {z}]\nintensity = 100\n"
            ),
            &dir.path().join("room.toml"),
        )
        .unwrap()
    };
    // (Row 0 is the floor point facing along the floor: `sparse` may mark it.)
    let edge_on = [on[3], on[4]];
    agree_flagged(
        "downlight on the ceiling",
        &illuminance(&ceiling(2.5), &edge_on, 25),
        &illuminance(&ceiling(2.5 - 1e-7), &edge_on, 26),
        bound,
        "ok",
        &[0],
    );
    // The same far from the origin (map coordinates): the light stands
    // just inside the room, not 5 m off it (a light on a surface was moved
    // 1e-6 of its coordinates off it to tell its region: below the floor,
    // so a wall point facing out of the room lost its `enclosed` flag, a
    // reviewer's find).
    let far = DVec3::new(5e5, 5e6, 0.0);
    let moved = parse(
        &format!(
            "[[surface]]\ntype = \"box\"\nmin = [{}, {}, 0]\nmax = [{}, {}, 2.5]\n\
             normals = \"inward\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[light]]\ntype = \"point\"\nposition = [{}, {}, 2.5]\nintensity = 100\n",
            far.x,
            far.y,
            far.x + 4.0,
            far.y + 3.0,
            far.x + 2.0,
            far.y + 1.5
        ),
        &dir.path().join("far.toml"),
    )
    .unwrap();
    let out_and_up = [
        (far + d(0.0, 1.5, 1.2), -DVec3::X),
        (far + d(0.0, 1.5, 1.2), DVec3::Z),
    ];
    let flags: Vec<String> = illuminance(&moved, &out_and_up, 29)
        .into_iter()
        .map(|r| r.2)
        .collect();
    assert_eq!(flags, ["enclosed", "ok"], "far from the origin");
    // On a solid's face, facing along it: a point on the box cabinet's
    // side facing up and one on a sphere's side facing up belong outside
    // the solid (they were flagged `enclosed`, left on the surface, and
    // read 11.6 against 16.3 and 17.0 against 22.0 lx; a reviewer's find).
    let solids = parse(
        &format!(
            "{BOX_ROOM}{CABINET}[[surface]]\ntype = \"sphere\"\ncenter = [3, 2.2, 0.5]\n\
             radius = 0.5\nmaterial = {{ type = \"lambertian\", reflectance = 0.7 }}\n{LIGHT}"
        ),
        &dir.path().join("room.toml"),
    )
    .unwrap();
    let on_solid = [(d(1.0, 1.5, 0.5), DVec3::Z), (d(2.5, 2.2, 0.5), DVec3::Z)];
    let off_solid = [
        (d(1.0 - 1e-6, 1.5, 0.5), DVec3::Z),
        (d(2.5 - 1e-6, 2.2, 0.5), DVec3::Z),
    ];
    agree_flagged(
        "on a solid, facing along it",
        &illuminance(&solids, &on_solid, 27),
        &illuminance(&solids, &off_solid, 28),
        bound,
        "ok",
        &[0, 1],
    );
    // A two-sided partition standing on the floor: a floor point at its
    // foot, edge-on to it, leaves the floor only (the first version slid it
    // up the partition's plane, out of the room: E_indirect 0, flagged
    // `ok`, a reviewer's find).
    let part = scene(
        &format!(
            "{BOX_ROOM}[[surface]]\ntype = \"rectangle\"\ncorner = [2, 1, 0]\nedge1 = [0, 1, 0]\n\
             edge2 = [0, 0, 1.5]\nsides = \"both\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.6 }}\n"
        ),
        dir.path(),
    );
    let tilted = d(0.0, 0.6, 0.8);
    let foot = [(d(2.0, 1.5, 0.0), tilted), (d(2.0, 1.5, 0.0), DVec3::Y)];
    let above = [(d(2.0, 1.5, 1e-6), tilted), (d(2.0, 1.5, 1e-6), DVec3::Y)];
    agree(
        "partition's foot",
        &illuminance(&part, &foot, 17),
        &illuminance(&part, &above, 18),
        bound,
    );
}
