//! Points in a slot: a board hung 1 cm in front of the points (its back,
//! towards them, black) lets light in only through the slit round it,
//! almost parallel to the points' plane. The only reflector is a lit floor,
//! so the light the points get is the floor's first reflection seen
//! through the slit, a 2-D integral over the floor strip the points see
//! (quadrature, sharing no code with the estimator). The near part's
//! grazing table ([`lumest::estimator::slot_table`]) must find that light.

mod common;
use common::chains_cfg;
use gauss_quad::legendre::GaussLegendre;
use glam::DVec3;
use lumest::estimator::Receivers;
use lumest::estimator::local::run;
use lumest::scene::parse;
use lumest::tally::sidak_bound;
use std::f64::consts::PI;

/// The plane of the points: `x = WALL`; the board's plane `x = WALL - GAP`,
/// spanning `[LO, HI]` in `y` and `z`.
const WALL: f64 = 2.0;
const GAP: f64 = 0.01;
const LO: f64 = 0.6;
const HI: f64 = 1.4;
/// The floor's reflectance and the point source (isotropic, \[cd\], \[m\]).
const RHO: f64 = 0.5;
const I: f64 = 1000.0;
const LIGHT: [f64; 3] = [1.0, 1.0, 1.5];

fn scene() -> lumest::scene::Scene {
    let src = format!(
        r#"
[[surface]]
type = "rectangle"
name = "floor"
corner = [-1, -1, 0]
edge1 = [4, 0, 0]
edge2 = [0, 4, 0]
material = {{ type = "lambertian", reflectance = {RHO} }}

[[surface]]
type = "rectangle"
name = "board"
corner = [{bx}, {LO}, {LO}]
edge1 = [0, {w}, 0]
edge2 = [0, 0, {w}]
sides = "back"
material = {{ type = "lambertian", reflectance = 0 }}

[[light]]
type = "point"
position = [{lx}, {ly}, {lz}]
intensity = {I}
"#,
        bx = WALL - GAP,
        w = HI - LO,
        lx = LIGHT[0],
        ly = LIGHT[1],
        lz = LIGHT[2],
    );
    parse(&src, std::path::Path::new("slot.toml")).unwrap()
}

/// Illuminance \[lx\] at `(WALL, yx, zx)` facing `-x`: the floor's radiance
/// `RHO E_d / pi` over the floor points `(WALL - delta, y, 0)` seen through
/// the slit. The segment to such a point crosses the board's plane at the
/// fraction `f = GAP / delta` of its length, below the board where
/// `delta < GAP / (1 - LO / zx)` and beside it where
/// `delta < GAP |y - yx| / (edge - yx)`; so for each `y` the strip
/// `0 < delta < max(those)` is seen.
fn through_slit(yx: f64, zx: f64) -> f64 {
    let rule = GaussLegendre::new(std::num::NonZeroUsize::new(20).unwrap());
    let below = GAP / (1.0 - LO / zx);
    let beside = |y: f64| {
        if y >= yx {
            GAP * (y - yx) / (HI - yx)
        } else {
            GAP * (yx - y) / (yx - LO)
        }
    };
    let g = |delta: f64, y: f64| {
        let v = DVec3::new(-delta, y - yx, -zx);
        let d2 = v.length_squared();
        let (cos_x, cos_y) = (delta / d2.sqrt(), zx / d2.sqrt());
        let l = DVec3::new(WALL - delta, y, 0.0) - DVec3::from(LIGHT);
        let e_d = I * LIGHT[2] / l.length().powi(3);
        RHO * e_d / PI * cos_x * cos_y / d2
    };
    let inner = |y: f64| {
        let top = below.max(beside(y));
        // Panels graded towards delta = 0, where the integrand vanishes
        // linearly, and up to the visible edge.
        let mut edges = vec![0.0, top / 64.0];
        while edges[edges.len() - 1] < top {
            let next = (2.0 * edges[edges.len() - 1]).min(top);
            edges.push(next);
        }
        edges
            .windows(2)
            .map(|w| rule.integrate(w[0], w[1], |d| g(d, y)))
            .sum::<f64>()
    };
    // Breaks where `beside` overtakes `below` and at the point's own `y`.
    let mut breaks = [
        -1.0,
        (yx - below / GAP * (yx - LO)).max(-1.0),
        yx,
        (yx + below / GAP * (HI - yx)).min(3.0),
        3.0,
    ];
    breaks.sort_by(f64::total_cmp);
    breaks
        .windows(2)
        .flat_map(|w| {
            let n = 64;
            (0..n).map(move |k| {
                let (a, b) = (w[0], w[1]);
                (
                    a + (b - a) * k as f64 / n as f64,
                    a + (b - a) * (k + 1) as f64 / n as f64,
                )
            })
        })
        .map(|(a, b)| rule.integrate(a, b, inner))
        .sum()
}

#[test]
fn light_through_a_slit_matches_quadrature() {
    let scene = scene();
    let spots = [(1.0, 1.0), (0.8, 0.9), (1.2, 1.25)];
    let pts: Vec<(DVec3, DVec3)> = spots
        .iter()
        .map(|&(y, z)| (DVec3::new(WALL, y, z), -DVec3::X))
        .collect();
    let rec = Receivers::new(&scene, &pts).unwrap();
    // Every point is in a slot: the near part covers what it sees through
    // the slit and draws grazing directions from its table.
    let auto = rec.clone().with_auto_near_field(&scene, 16);
    for j in 0..pts.len() {
        assert!(rec.enclosed(j), "point {j} not enclosed");
        assert!(
            auto.near_path_setup(j).0.is_some(),
            "point {j} not in a slot"
        );
    }
    let r = run(&scene, &auto, &chains_cfg(1 << 20, 3, 0), &mut |_| true);
    let bound = sidak_bound(1e-3, pts.len(), None);
    for (j, &(y, z)) in spots.iter().enumerate() {
        let exact = through_slit(y, z);
        let t = &r.tallies.estimated[j];
        let (m, se) = (t.mean(), t.std_error());
        println!("point {j}: {m:.6e} +- {se:.2e} against {exact:.6e}");
        // Precise enough that a 2 % error lies beyond the bound.
        assert!(se < 0.005 * exact, "point {j}: se {se} of {exact}");
        assert!(
            ((m - exact) / se).abs() < bound,
            "point {j}: {m} +- {se} against {exact}"
        );
    }
}

#[test]
fn points_at_or_near_the_board_edge_keep_the_plain_split() {
    // 2 mm inside the board's edge a point sees half the room (the table's
    // mean reach about 0.5), 1 cm inside it light still gets in through
    // several per cent of its hemisphere: neither is a slot, so both keep
    // the radius they need and cosine-sampled near paths. 30 cm inside,
    // the point is one.
    let scene = scene();
    let pts: Vec<(DVec3, DVec3)> = [(HI - 0.002, 1.0), (HI - 0.01, 1.0), (HI - 0.3, 1.0)]
        .iter()
        .map(|&(y, z)| (DVec3::new(WALL, y, z), -DVec3::X))
        .collect();
    let rec = Receivers::new(&scene, &pts).unwrap();
    let auto = rec.clone().with_auto_near_field(&scene, 16);
    let plain = rec.clone().with_near_field(0.0, 16);
    let (_, radii) = auto.near_field();
    for (j, &r) in radii.iter().enumerate().take(2) {
        assert!(rec.enclosed(j), "point {j} not enclosed");
        assert!(auto.near_path_setup(j).0.is_none(), "point {j} made a slot");
        // (A quarter of the distance to the light: well below a slot's.)
        assert!(r > 0.0 && r < 0.5, "point {j}: radius {r}");
    }
    assert!(auto.near_path_setup(2).0.is_some() && radii[2] > 1.0);
    // A fixed radius asked after the automatic one drops the slots.
    let fixed = auto.clone().with_near_field(0.05, 16);
    assert!((0..3).all(|j| fixed.near_path_setup(j).0.is_none()));
    assert!((0..3).all(|j| plain.near_path_setup(j).0.is_none()));
}

/// A reflecting room (reflectance 0.5, a white board front 0.6): the light
/// through the slit has been reflected any number of times, so the slot
/// points' near paths go on past the floor with their vertices' own split
/// (pool joins, next segments). Against the plain local estimate (no near
/// part: the wall is coplanar with the points and the board's back black,
/// so its kernel stays bounded there) at 4 times the chains.
#[test]
fn slot_points_in_a_reflecting_room_match_the_plain_estimate() {
    let src = r#"
[[surface]]
type = "box"
name = "room"
min = [0, 0, 0]
max = [4, 3, 2.8]
normals = "inward"
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
type = "rectangle"
name = "board"
corner = [3.99, 0.9, 0.8]
edge1 = [0, 1.2, 0]
edge2 = [0, 0, 1.0]
sides = "back"
material = { type = "lambertian", reflectance = 0.6 }

[[light]]
type = "point"
position = [2.0, 1.5, 2.5]
intensity = 1000
"#;
    let scene = parse(src, std::path::Path::new("room.toml")).unwrap();
    let pts: Vec<(DVec3, DVec3)> = [(1.5, 1.3), (1.2, 1.0), (1.8, 1.6)]
        .iter()
        .map(|&(y, z)| (DVec3::new(4.0, y, z), -DVec3::X))
        .collect();
    let rec = Receivers::new(&scene, &pts).unwrap();
    let auto = rec.clone().with_auto_near_field(&scene, 16);
    for j in 0..pts.len() {
        assert!(
            auto.near_path_setup(j).0.is_some(),
            "point {j} not in a slot"
        );
    }
    let slot = run(&scene, &auto, &chains_cfg(1 << 21, 3, 0), &mut |_| true);
    let plain_cfg = lumest::run::RunConfig {
        near_auto: false,
        ..chains_cfg(1 << 23, 4, 0)
    };
    let plain = run(&scene, &rec, &plain_cfg, &mut |_| true);
    let bound = sidak_bound(1e-3, pts.len(), None);
    for j in 0..pts.len() {
        let (a, b, se) = common::apart(&slot, &plain, j);
        println!("point {j}: slot {a:.6e} plain {b:.6e} +- {se:.2e}");
        assert!(
            ((a - b) / se).abs() < bound,
            "point {j}: {a} against {b} +- {se}"
        );
        // Precise enough that a 2 % error (a share of the light counted
        // twice or lost at the vertices) lies beyond the bound.
        assert!(se < 0.005 * b, "point {j}: se {se} of {b}");
    }
}
