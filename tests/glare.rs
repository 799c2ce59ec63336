//! `lumest glare`: the Unified Glare Rating against a case computed by hand.
//!
//! An isotropic luminaire (100 cd in every direction, a 0.3 m x 0.3 m
//! luminous opening facing down) at the centre of an integrating sphere of
//! radius 2 m (reflectance 0.5). In a sphere, light reflected off the wall
//! illuminates the wall uniformly, and an isotropic source at the centre
//! lights it uniformly too, so every reflected order has a uniform wall
//! luminance: the indirect illuminance at any inside point, on any plane,
//! is `pi L_wall = rho / (1 - rho) * I / R^2 = 25 lx` exactly. The glare sum
//! `L^2 omega / p^2` of the one luminaire is worked out here from the
//! geometry and Guth's formula, written again; the rating follows.

use assert_cmd::Command;
use std::f64::consts::PI;

const IES: &str = "IESNA:LM-63-2002\n[TEST] lumest glare\nTILT=NONE\n\
1 -1 1 3 1 1 2 0.3 0.3 0\n1 1 0\n0 90 180\n0\n100 100 100\n";

const SCENE: &str = r#"[[surface]]
type = "sphere"
center = [0, 0, 0]
radius = 2
sides = "inside"
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "ies"
name = "lum"
file = "lum.ies"
position = [0, 0, 0]
"#;

/// Guth's position index by its published formula (tau, sigma in degrees).
fn guth(tau: f64, sigma: f64) -> f64 {
    let a = 35.2 - 0.31889 * tau - 1.22 * (-2.0 * tau / 9.0).exp();
    let b = 21.0 + 0.26667 * tau - 0.002963 * tau * tau;
    (a * 1e-3 * sigma + b * 1e-5 * sigma * sigma).exp()
}

/// The glare sum of the luminaire at the origin seen from an eye at `e`
/// looking along +x: `R = -e_x`, `T = e_y` (the luminaire lies to the
/// right, -y, when e_y > 0), `H = -e_z`; the eye below sees the bottom
/// opening at `cos gamma = H / d`.
fn by_hand(e: [f64; 3]) -> f64 {
    let (r, t, h) = (-e[0], e[1], -e[2]);
    let d = (r * r + t * t + h * h).sqrt();
    let a_p = 0.09 * h / d;
    let l = 100.0 / a_p;
    let omega = a_p / (d * d);
    let tau = t.abs().atan2(h).to_degrees();
    let sigma = (t * t + h * h).sqrt().atan2(r).to_degrees();
    let p = guth(tau, sigma);
    l * l * omega / (p * p)
}

fn column(header: &[&str], name: &str) -> usize {
    header.iter().position(|h| *h == name).unwrap()
}

#[test]
fn single_luminaire_in_a_sphere_matches_the_hand_computation() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lum.ies"), IES).unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let obs = dir.path().join("obs.csv");
    let eyes = [[-1.0, 0.0, -0.5], [-1.0, 0.6, -0.4], [-1.5, -0.3, -0.9]];
    let mut csv = "name,x,y,z,dx,dy,dz\n".to_string();
    for (k, e) in eyes.iter().enumerate() {
        csv += &format!("o{k},{},{},{},1,0,0\n", e[0], e[1], e[2]);
    }
    // Looking away from the luminaire: none in view, no rating.
    csv += "away,-1,0,-0.5,-1,0,0\n";
    std::fs::write(&obs, csv).unwrap();
    let out = dir.path().join("g.csv");
    lumest()
        .args(["glare", "--quiet", "--chains", "200000", "--scene"])
        .arg(&scene)
        .arg("--observers")
        .arg(&obs)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let num = |row: &Vec<&str>, name: &str| -> f64 { row[column(&header, name)].parse().unwrap() };
    // Sidak over the 3 observers, two-sided 1 % in all.
    let zb = lumest::tally::sidak_bound(0.01, 3, None);
    let e_exact = 25.0;
    for (row, e) in rows.iter().zip(&eyes) {
        // The luminaire term is exact.
        let s = by_hand(*e);
        let got = num(row, "glare_sum");
        assert!((got / s - 1.0).abs() < 1e-9, "glare sum {got} vs {s}");
        // The background: the Monte Carlo estimate against 25 lx.
        let (ei, se) = (num(row, "E_ind"), num(row, "E_ind_stderr"));
        assert!((ei - e_exact).abs() <= zb * se, "E_ind {ei} +- {se}");
        assert!(zb * se < 0.02 * e_exact, "too imprecise to see 2 %: {se}");
        let ugr_ref = 8.0 * (0.25 * PI * s / e_exact).log10();
        let (u, use_) = (num(row, "UGR"), num(row, "UGR_stderr"));
        assert!(
            (u - ugr_ref).abs() <= zb * use_,
            "UGR {u} +- {use_} vs {ugr_ref}"
        );
        assert!(zb * use_ < 0.02 * ugr_ref, "UGR too imprecise: {use_}");
        assert!(
            (use_ - 8.0 / std::f64::consts::LN_10 * se / ei).abs() < 1e-9 * use_,
            "delta-method error"
        );
        let (lo, hi) = (num(row, "UGR_ci95_low"), num(row, "UGR_ci95_high"));
        assert!(lo < u && u < hi);
        assert!((num(row, "Lb") - ei / PI).abs() < 1e-12 * ei);
        assert_eq!(row[column(&header, "luminaires")], "1");
    }
    let away = &rows[3];
    assert_eq!(away[column(&header, "UGR")], "");
    assert_eq!(away[column(&header, "luminaires")], "0");
    assert!(away[column(&header, "UGR_flag")].contains("no_luminaire"));
}

#[test]
fn lights_without_a_luminous_area_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        "[[surface]]\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"point\"\nname = \"bulb\"\nposition = [0, 0, 2]\nintensity = 10\n",
    )
    .unwrap();
    let obs = dir.path().join("obs.csv");
    std::fs::write(&obs, "x,y,z,dx,dy,dz\n-1,0,1.2,1,0,0\n").unwrap();
    let err = lumest()
        .args(["glare", "--quiet", "--scene"])
        .arg(&scene)
        .arg("--observers")
        .arg(&obs)
        .arg("--out")
        .arg(dir.path().join("g.csv"))
        .assert()
        .failure();
    let msg = String::from_utf8_lossy(&err.get_output().stderr).to_string();
    assert!(
        msg.contains("bulb") && msg.contains("luminous area"),
        "{msg}"
    );
    // A vertical line of sight: refused with file and line.
    std::fs::write(dir.path().join("lum.ies"), IES).unwrap();
    std::fs::write(&scene, SCENE).unwrap();
    std::fs::write(&obs, "x,y,z,dx,dy,dz\n-1,0,-0.5,0,0,1\n").unwrap();
    let err = lumest()
        .args(["glare", "--quiet", "--scene"])
        .arg(&scene)
        .arg("--observers")
        .arg(&obs)
        .arg("--out")
        .arg(dir.path().join("g.csv"))
        .assert()
        .failure();
    let msg = String::from_utf8_lossy(&err.get_output().stderr).to_string();
    assert!(
        msg.contains("obs.csv:2") && msg.contains("vertical"),
        "{msg}"
    );
}

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

/// The standard room of the tabular method (CIE 117): 8 m x 8 m (4H x 4H,
/// H = 2 m above the eye at 1.2 m), 16 x 16 luminaires at the spacing
/// 0.25 H, reflectances 0.7 / 0.5 / 0.2, the observer at the middle of a
/// wall looking across the room along `+x`. The luminaire `file` (in
/// `dir`) turned by `rotate` \[deg\] about its nadir.
fn standard_room(dir: &std::path::Path, file: &str, rotate: f64) -> std::path::PathBuf {
    let mut s = String::from(
        "[[surface]]\ntype = \"box\"\nname = \"room\"\nmin = [0, 0, 0]\nmax = [8, 8, 3.2]\n\
         normals = \"inward\"\nmaterial = { type = \"lambertian\", reflectance = 0.5 }\n\
         faces = { z_min = { type = \"lambertian\", reflectance = 0.2 }, \
         z_max = { type = \"lambertian\", reflectance = 0.7 } }\n",
    );
    for i in 0..16 {
        for j in 0..16 {
            s += &format!(
                "\n[[light]]\ntype = \"ies\"\nfile = \"{file}\"\nposition = [{}, {}, 3.2]\nrotate = {rotate}\n",
                (f64::from(i) + 0.5) * 0.5,
                (f64::from(j) + 0.5) * 0.5
            );
        }
    }
    let path = dir.join("room.toml");
    std::fs::write(&path, s).unwrap();
    path
}

/// A cosine (Lambertian) downlight of 100 cd on the nadir with a 0.3 m x
/// 0.3 m opening, as an IES file in `dir`.
fn cosine_ies(dir: &std::path::Path) {
    let mut v: Vec<String> = (0..=90).map(|g| g.to_string()).collect();
    v.push("180".into());
    let mut c: Vec<String> = (0..=90)
        .map(|g| format!("{:.17e}", 100.0 * f64::from(g).to_radians().cos()))
        .collect();
    c[90] = "0".into();
    c.push("0".into());
    std::fs::write(
        dir.join("cos.ies"),
        format!(
            "IESNA:LM-63-2002\n[TEST] cosine\nTILT=NONE\n1 -1 1 {} 1 1 2 0.3 0.3 0\n1 1 0\n{}\n0\n{}\n",
            v.len(),
            v.join(" "),
            c.join(" ")
        ),
    )
    .unwrap();
}

/// `lumest glare` at the standard room's observer: the result row's
/// columns by name.
fn rate_standard_room(dir: &std::path::Path, scene: &std::path::Path) -> Vec<(String, String)> {
    let obs = dir.join("obs.csv");
    std::fs::write(&obs, "name,x,y,z,dx,dy,dz\nwall,0.001,4,1.2,1,0,0\n").unwrap();
    let out = dir.join("g.csv");
    lumest()
        .args(["glare", "--quiet", "--chains", "100000", "--scene"])
        .arg(scene)
        .arg("--observers")
        .arg(&obs)
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from);
    let row = lines.next().unwrap().split(',').map(String::from);
    header.zip(row).collect()
}

fn num(row: &[(String, String)], name: &str) -> f64 {
    row.iter()
        .find(|(h, _)| h == name)
        .unwrap()
        .1
        .parse()
        .unwrap()
}

const ROOM_4H: lumest::glare::tabular::StandardRoom = lumest::glare::tabular::StandardRoom {
    across: 8.0,
    along: 8.0,
    eye: 1.2,
    h: 2.0,
    spacing: 0.5,
    rho: [0.7, 0.5, 0.2],
};

/// The cosine downlight, as the tabular method sees it.
struct Cosine;

impl lumest::glare::tabular::TableLuminaire for Cosine {
    fn intensity(&self, w: glam::DVec3) -> f64 {
        100.0 * (-w.z).max(0.0)
    }
    fn projected_area(&self, w: glam::DVec3) -> f64 {
        0.09 * (-w.z).max(0.0)
    }
}

#[test]
fn standard_room_against_the_tabular_method() {
    let dir = tempfile::tempdir().unwrap();
    cosine_ies(dir.path());
    let scene = standard_room(dir.path(), "cos.ies", 0.0);
    let row = rate_standard_room(dir.path(), &scene);
    let tab = ROOM_4H.rating(&Cosine);
    // The luminaire terms: the same geometry (but the scene's eye 1 mm off
    // the wall), lumest's through the IES table (cos interpolated linearly
    // in 1-degree steps) and the scene.
    assert!((num(&row, "glare_sum") / tab.sum - 1.0).abs() < 1e-3);
    // The luminaires that count: those whose nearest node of CIE 117's
    // Table 4.1 (`T/R` 0 .. 3, `H/R` 0 .. 1.9, steps of 0.1) holds an
    // index, the dashes where the brows hide a source excepted.
    let dash = |t: i64, h: i64| (t <= 3 && h >= 18) || (t <= 8 && h == 19);
    let mut counted = 0;
    for i in 0..16 {
        for j in 0..16 {
            let r = (f64::from(i) + 0.5) * 0.5 - 0.001;
            let t = ((f64::from(j) + 0.5) * 0.5 - 4.0).abs();
            let (nt, nh) = (
                (10.0 * t / r).round() as i64,
                (10.0 * 2.0 / r).round() as i64,
            );
            if nt <= 30 && nh <= 19 && !dash(nt, nh) {
                counted += 1;
            }
        }
    }
    assert!(counted < 256);
    assert_eq!(num(&row, "luminaires"), f64::from(counted));
    // The background: the eye's indirect illuminance against the walls'
    // average, the tables' approximation (measured: 217.0 +- 0.5 lx against
    // 221.5 lx, UGR 16.95 against 16.88). A bound of 0.25 UGR units is
    // about 7 % in the background.
    assert!(
        (num(&row, "UGR") - tab.ugr).abs() < 0.25,
        "UGR {} against the tabular {}",
        num(&row, "UGR"),
        tab.ugr
    );
    assert!((num(&row, "E_ind") / tab.e_wall_ind - 1.0).abs() < 0.07);
    eprintln!(
        "tabular: sum {} E_W {} UGR {}; lumest glare: sum {} E_ind {} +- {} UGR {} +- {}",
        tab.sum,
        tab.e_wall_ind,
        tab.ugr,
        num(&row, "glare_sum"),
        num(&row, "E_ind"),
        num(&row, "E_ind_stderr"),
        num(&row, "UGR"),
        num(&row, "UGR_stderr")
    );
}

/// A luminaire with a narrow beam in C90-C270 (`sym_quadrant.ies`: 43
/// degrees there, 120 in C0-C180; a 0.2 m x 0.3 m opening), viewed
/// crosswise (turned 90 degrees: C0 across the line of sight) and endwise,
/// by `lumest glare` in the scene and by the UGR table's own code for the
/// 4H x 4H room. The luminaire sums agree to the table interpolation; the
/// ratings to the tables' background approximation; and the two views
/// differ, so a table that swapped them would fail.
#[test]
fn standard_room_table_rows_viewed_crosswise_and_endwise() {
    use lumest::glare::tabular::{FileLuminaire, View, hemisphere_fluxes};
    let dir = tempfile::tempdir().unwrap();
    let src =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/photometry/sym_quadrant.ies");
    std::fs::copy(&src, dir.path().join("q.ies")).unwrap();
    let p = lumest::io::photometry::read(&src).unwrap();
    let g = lumest::light::Goniometric::new(&p, 1.0);
    let area = lumest::glare::LuminousArea::of_file(&p.opening).unwrap();
    let mut ugr = Vec::new();
    for (view, rotate) in [(View::Crosswise, 90.0), (View::Endwise, 0.0)] {
        let lum = FileLuminaire {
            dist: &g,
            area: &area,
            frame: view.frame(),
        };
        let sum = ROOM_4H.glare_sum(&lum);
        let e_w = ROOM_4H.wall_indirect(&ROOM_4H.direct_flux(&lum, hemisphere_fluxes(&lum)));
        let tab = 8.0 * (0.25 * PI * sum / e_w).log10();
        let scene = standard_room(dir.path(), "q.ies", rotate);
        let row = rate_standard_room(dir.path(), &scene);
        eprintln!(
            "{view:?}: tabular sum {sum} E_W {e_w} UGR {tab}; lumest glare: sum {} E_ind {} +- {} UGR {}",
            num(&row, "glare_sum"),
            num(&row, "E_ind"),
            num(&row, "E_ind_stderr"),
            num(&row, "UGR")
        );
        // The scene's eye is 1 mm off the wall (0.1 mm of the sum here).
        assert!(
            (num(&row, "glare_sum") / sum - 1.0).abs() < 1e-3,
            "{view:?}"
        );
        assert!((num(&row, "UGR") - tab).abs() < 0.25, "{view:?}");
        ugr.push((tab, num(&row, "UGR")));
    }
    assert!(
        (ugr[0].0 - ugr[1].0).abs() > 0.5 && (ugr[0].1 - ugr[1].1).abs() > 0.5,
        "{ugr:?}"
    );
}

/// The luminous area's visible part: the isotropic luminaire above at
/// (0, 0, 3), seen from the eye at (-3, 0, 1.2) looking along +x, with a
/// screen 0.1 mm below its opening. A screen over `y >= 0` hides the half
/// of the opening on that side (every sight line to it stays at `y > 0`,
/// the eye being at `y = 0`): the term keeps its luminance and halves its
/// solid angle. A screen over the whole opening hides it: no term. Without
/// a screen the whole area counts.
#[test]
fn a_partly_hidden_luminaire_counts_the_part_the_eye_sees() {
    use glam::DVec3;
    use lumest::glare::{Observer, glare_term, luminous_area};
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("lum.ies"), IES).unwrap();
    let light =
        "[[light]]\ntype = \"ies\"\nname = \"lum\"\nfile = \"lum.ies\"\nposition = [0, 0, 3]\n";
    let screen = |y0: f64| {
        format!(
            "[[surface]]\ntype = \"rectangle\"\ncorner = [-1, {y0}, 2.9999]\nedge1 = [2, 0, 0]\n\
             edge2 = [0, {}, 0]\nsides = \"both\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n",
            1.0 - y0
        )
    };
    let term = |extra: &str| {
        let path = dir.path().join("s.toml");
        std::fs::write(&path, format!("{extra}\n{light}")).unwrap();
        let scene = lumest::scene::load(&path).unwrap();
        let area = luminous_area(&scene.lights[0]).unwrap().unwrap();
        let obs = Observer::new(DVec3::new(-3.0, 0.0, 1.2), DVec3::X).unwrap();
        glare_term(&scene, 0, &area, &obs)
    };
    // A far-off screen, so that every scene has a surface.
    let open = term(&screen(50.0).replace("2.9999", "-40")).unwrap();
    let half = term(&screen(0.0)).unwrap();
    assert_eq!(open.seen, 1.0);
    // The hand geometry: a 0.3 m x 0.3 m opening at d from the eye.
    let (r, h) = (3.0f64, 1.8f64);
    let d = (r * r + h * h).sqrt();
    let omega = 0.09 * (h / d) / (d * d);
    assert!(
        (open.omega / omega - 1.0).abs() < 1e-12,
        "{} vs {omega}",
        open.omega
    );
    assert_eq!(half.seen, 0.5);
    assert_eq!(half.l, open.l);
    assert!((half.omega / open.omega - 0.5).abs() < 1e-12);
    assert!((half.value() / open.value() - 0.5).abs() < 1e-12);
    assert!(term(&screen(-1.0)).is_none());
    // A screen whose edge runs obliquely across the opening, y = k x + y0
    // in its plane: the eye sees the part of the opening on one side of a
    // line, whose area is clipped exactly here. The 8 x 8 cell centres used
    // before resolved such an edge to a cell (a screen edge along a row of
    // cells read 0.375 against 0.350, 0.24 UGR).
    for (k, y0) in [(0.3, 0.02), (-0.05, -0.1), (2.5, 0.13)] {
        let slanted = format!(
            "[[surface]]\ntype = \"rectangle\"\ncorner = [-1, {}, 2.9999]\nedge1 = [2, {}, 0]\n\
             edge2 = [0, 1, 0]\nsides = \"both\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n",
            y0 - k,
            2.0 * k
        );
        let t = term(&slanted).unwrap();
        // The sight line from the eye to (x, y, 3) crosses the screen's
        // plane at s = 1.7999 / 1.8 of the way, at (-3 + s (x + 3), s y):
        // seen where y - k x < c.
        let s = 1.7999 / 1.8;
        let c = (y0 + 3.0 * k * (s - 1.0)) / s;
        let exact = half_square_area(0.15, k, c) / 0.09;
        assert!(
            (t.seen - exact).abs() < 2e-3 && exact > 0.05 && exact < 0.95,
            "edge y = {k} x + {y0}: seen {} against {exact}",
            t.seen
        );
    }
}

/// Area of `{(x, y) in [-a, a]^2 : y - k x < c}`: the square clipped by
/// the half-plane (Sutherland-Hodgman), by the shoelace formula.
fn half_square_area(a: f64, k: f64, c: f64) -> f64 {
    let square = [(-a, -a), (a, -a), (a, a), (-a, a)];
    let f = |p: (f64, f64)| c - (p.1 - k * p.0);
    let mut poly = Vec::new();
    for i in 0..4 {
        let (p, q) = (square[i], square[(i + 1) % 4]);
        if f(p) >= 0.0 {
            poly.push(p);
        }
        if (f(p) >= 0.0) != (f(q) >= 0.0) {
            let t = f(p) / (f(p) - f(q));
            poly.push((p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1)));
        }
    }
    let n = poly.len();
    (0..n)
        .map(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % n]);
            p.0 * q.1 - q.0 * p.1
        })
        .sum::<f64>()
        .abs()
        / 2.0
}

/// The scene file's `[[observer]]` tables rate as the same observers given
/// by CSV: the office's three, every result column the same text (the
/// same chains; the eye columns are written from the numbers, `3` for the
/// CSV's `3.0`). A vertical line of sight is refused with the file, line
/// and field; a scene without observers and without `--observers` says
/// how to give them.
#[test]
fn scene_observers_rate_as_the_csv_observers() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], out: &std::path::Path| {
        lumest()
            .args(["glare", "--quiet", "--chains", "16384", "--scene"])
            .arg(root.join("data/office.toml"))
            .args(extra)
            .arg("--out")
            .arg(out)
            .assert()
            .success();
        std::fs::read_to_string(out).unwrap()
    };
    let csv = root.join("data/office_observers.csv");
    let a = run(&[], &dir.path().join("a.csv"));
    let b = run(
        &["--observers", csv.to_str().unwrap()],
        &dir.path().join("b.csv"),
    );
    let rows = |t: &str| -> Vec<Vec<String>> {
        t.lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect()
    };
    let (ra, rb) = (rows(&a), rows(&b));
    assert_eq!(ra.len(), 4);
    assert_eq!(ra[0], rb[0]);
    for (x, y) in ra.iter().zip(&rb).skip(1) {
        assert_eq!(x[0], y[0]);
        for c in 1..7 {
            assert_eq!(x[c].parse::<f64>().unwrap(), y[c].parse::<f64>().unwrap());
        }
        assert_eq!(x[7..], y[7..]);
    }
    // The error `lumest glare` gives for the scene `text` without --observers.
    std::fs::write(dir.path().join("lum.ies"), IES).unwrap();
    let bad = dir.path().join("bad.toml");
    let error = |text: &str| {
        std::fs::write(&bad, text).unwrap();
        let out = lumest()
            .args(["glare", "--quiet", "--scene"])
            .arg(&bad)
            .arg("--out")
            .arg(dir.path().join("c.csv"))
            .assert()
            .failure();
        String::from_utf8_lossy(&out.get_output().stderr).to_string()
    };
    // A vertical line of sight (the sphere scene above, and an observer).
    let text = format!("{SCENE}\n[[observer]]\neye = [0, 0, -1]\nview = [0, 0, -1]\n");
    let line = text.lines().position(|l| l.starts_with("view")).unwrap() + 1;
    let err = error(&text);
    assert!(
        err.contains(&format!("bad.toml:{line}"))
            && err.contains("view")
            && err.contains("vertical"),
        "{err}"
    );
    // No observers anywhere.
    let err = error(SCENE);
    assert!(
        err.contains("[[observer]]") && err.contains("--observers"),
        "{err}"
    );
}

/// A spherical luminaire (LM-63-2002 sphere: width, length and height all
/// -0.4 m; 100 cd in every direction) at (0, 0, 3), seen side-on from the
/// eye at (-3, 0, 3) looking at it along +x: its luminance is `I / (pi r^2)`
/// and its solid angle `pi r^2 / d^2` with `r = 0.2 m`, `d = 3 m`, the
/// position index 1 (on the line of sight). The former reading (a disc
/// with cylinder sides) gave the area `D^2`, 27 % more.
#[test]
fn a_spherical_luminaire_seen_side_on_matches_the_hand_values() {
    use glam::DVec3;
    use lumest::glare::{Observer, glare_term, luminous_area};
    let dir = tempfile::tempdir().unwrap();
    let ies = "IESNA:LM-63-2002\n[TEST] sphere\nTILT=NONE\n\
               1 -1 1 3 1 1 2 -0.4 -0.4 -0.4\n1 1 0\n0 90 180\n0\n100 100 100\n";
    std::fs::write(dir.path().join("lum.ies"), ies).unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(
        &path,
        "[[surface]]\ntype = \"rectangle\"\ncorner = [-50, -50, -40]\nedge1 = [100, 0, 0]\n\
         edge2 = [0, 100, 0]\nsides = \"both\"\nmaterial = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"ies\"\nname = \"lum\"\nfile = \"lum.ies\"\nposition = [0, 0, 3]\n",
    )
    .unwrap();
    let scene = lumest::scene::load(&path).unwrap();
    let area = luminous_area(&scene.lights[0]).unwrap().unwrap();
    let (r, d) = (0.2f64, 3.0f64);
    let obs = Observer::new(DVec3::new(-d, 0.0, 3.0), DVec3::X).unwrap();
    let t = glare_term(&scene, 0, &area, &obs).unwrap();
    let (l, omega) = (100.0 / (PI * r * r), PI * r * r / (d * d));
    assert!((t.l / l - 1.0).abs() < 1e-12, "L {} vs {l}", t.l);
    assert!(
        (t.omega / omega - 1.0).abs() < 1e-12,
        "omega {} vs {omega}",
        t.omega
    );
    assert_eq!((t.p, t.seen), (1.0, 1.0));
    assert!((t.value() / (l * l * omega) - 1.0).abs() < 1e-12);
    // From below and obliquely the sphere is the same disc (eyes within
    // the position index's field, `H/R` 0.9 and 1.25).
    for eye in [DVec3::new(-2.0, 0.5, 1.2), DVec3::new(-2.0, -1.0, 0.5)] {
        let obs = Observer::new(eye, DVec3::new(1.0, 0.0, 0.0)).unwrap();
        let t = glare_term(&scene, 0, &area, &obs).unwrap();
        let d = (DVec3::new(0.0, 0.0, 3.0) - eye).length();
        assert!((t.l / l - 1.0).abs() < 1e-12);
        assert!((t.omega / (PI * r * r / (d * d)) - 1.0).abs() < 1e-12);
    }
}

/// A result column's name in the observers CSV is refused before the run,
/// `UGR_verdict` too when --ugr-limit adds that column (the output had two
/// `UGR_verdict` columns, a reader taking the first got the input's).
#[test]
fn result_column_names_in_the_observers_are_refused_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    cosine_ies(dir.path());
    let scene = standard_room(dir.path(), "cos.ies", 0.0);
    let obs = dir.path().join("obs.csv");
    std::fs::write(
        &obs,
        "name,x,y,z,dx,dy,dz,UGR_verdict\nwall,0.001,4,1.2,1,0,0,target\n",
    )
    .unwrap();
    let out = dir.path().join("g.csv");
    let run = |limit: bool| {
        let mut c = lumest();
        c.args(["glare", "--quiet", "--chains", "1024", "--scene"])
            .arg(&scene)
            .arg("--observers")
            .arg(&obs)
            .arg("--out")
            .arg(&out);
        if limit {
            c.args(["--ugr-limit", "19"]);
        }
        c.output().unwrap()
    };
    let o = run(true);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("column `UGR_verdict` has the name of a result column"),
        "{err}"
    );
    assert!(!out.exists());
    // Without --ugr-limit the column is the input's own and is kept.
    let o = run(false);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let header = std::fs::read_to_string(&out).unwrap();
    let header = header.lines().next().unwrap();
    assert_eq!(header.matches("UGR_verdict").count(), 1, "{header}");
}
