//! `lumest grid` and the grid figures of `lumest illuminance --figures-out`.

use assert_cmd::Command;

const SCENE: &str = r#"[[surface]]
type = "box"
name = "room"
min = [0, 0, 0]
max = [4, 3, 2.5]
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "point"
position = [2, 1.5, 2.3]
intensity = 300

[[grid]]
name = "work plane"
surface = "room.z_min"
offset = 0.8
border = 0.5
em = 1
u0 = 0.1
maintenance_factor = 0.8

[[grid]]
name = "wall"
surface = "room.x_max"
spacing = 1
em = 1e6
"#;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

/// `lumest illuminance --chains N --quiet` on `scene` and `points`, writing
/// `out`, with `extra` arguments.
fn illuminance(
    chains: &str,
    scene: &std::path::Path,
    points: &std::path::Path,
    out: &std::path::Path,
    extra: &[&std::ffi::OsStr],
) -> std::process::Output {
    lumest()
        .args(["illuminance", "--chains", chains, "--quiet", "--scene"])
        .arg(scene)
        .arg("--points")
        .arg(points)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// `scene` written to `dir/s.toml`, and the points of its grid `name` by
/// `lumest grid` in `dir/p.csv`: (scene path, points path).
fn grid_points(
    dir: &std::path::Path,
    scene: &str,
    name: &str,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let (s, p) = (dir.join("s.toml"), dir.join("p.csv"));
    std::fs::write(&s, scene).unwrap();
    lumest()
        .args(["grid", "--name", name, "--scene"])
        .arg(&s)
        .arg("--out")
        .arg(&p)
        .assert()
        .success();
    (s, p)
}

#[test]
fn grid_writes_points_and_illuminance_writes_figures() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let points = dir.path().join("p.csv");
    let out = lumest()
        .args(["grid", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&points)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let text = std::fs::read_to_string(&points).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "id,grid,x,y,z,nx,ny,nz,area,receiver"
    );
    // Work plane 3 x 2 m: d = 3 m, p = 0.43 m, 7 x 5 cells; wall 3 x 2.5 m at 1 m: 3 x 3.
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 35 + 9, "{err}");
    assert!(rows[0].starts_with("1,work plane,") && rows[0].ends_with(",planar"));
    assert!(rows[35].starts_with("1,wall,4,"), "{}", rows[35]);
    assert!(
        err.contains("grid `work plane`: 35 points (7 x 5 cells"),
        "{err}"
    );

    // One grid by name; an unknown name.
    let one = dir.path().join("one.csv");
    lumest()
        .args(["grid", "--name", "wall", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&one)
        .assert()
        .success();
    assert_eq!(std::fs::read_to_string(&one).unwrap().lines().count(), 10);
    let out = lumest()
        .args(["grid", "--name", "floor", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&one)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no grid of that name"));

    // The run: figures per grid, with verdicts.
    let res = dir.path().join("e.csv");
    let figs = dir.path().join("f.csv");
    let out = illuminance(
        "16384",
        &scene,
        &points,
        &res,
        &["--figures-out".as_ref(), figs.as_ref()],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let f = std::fs::read_to_string(&figs).unwrap();
    let mut lines = f.lines();
    assert_eq!(
        lines.next().unwrap(),
        "grid,figure,unit,value,std_error,ci95_low,ci95_high,bias,method,required,verdict,points,left_out,flagged,area,maintenance_factor,batches"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 10);
    let names: Vec<(&str, &str)> = rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(
        names[..5],
        [
            ("work plane", "E_avg"),
            ("work plane", "E_min"),
            ("work plane", "E_max"),
            ("work plane", "U0"),
            ("work plane", "Ud"),
        ]
    );
    // Em 1 lx and U0 0.1 are met, 1e6 lx is not; the others have no requirement.
    assert_eq!((rows[0][9], rows[0][10]), ("1", "met"));
    assert_eq!((rows[3][9], rows[3][10]), ("0.1", "met"));
    assert_eq!((rows[5][9], rows[5][10]), ("1000000", "not met"));
    assert_eq!(rows[1][10], "");
    assert_eq!(rows[0][8], "batch-means");
    assert!(rows[1][8].starts_with("bootstrap-") && rows[1][8].ends_with("+t-bounds"));
    // Area weights: 6 m^2 of work plane and 7.5 m^2 of wall; factor 0.8, then 1.
    assert!((rows[0][14].parse::<f64>().unwrap() - 6.0).abs() < 1e-9);
    assert!((rows[5][14].parse::<f64>().unwrap() - 7.5).abs() < 1e-9);
    assert_eq!((rows[0][15], rows[5][15]), ("0.8", "1"));
    // Every value lies in its interval; E_min <= E_avg <= E_max.
    for r in &rows {
        let v: Vec<f64> = r[3..7].iter().map(|x| x.parse().unwrap()).collect();
        assert!(v[2] <= v[0] && v[0] <= v[3] && v[1] > 0.0, "{r:?}");
    }
    let e = |r: usize| rows[r][3].parse::<f64>().unwrap();
    assert!(e(1) <= e(0) && e(0) <= e(2));
    // The summary.
    assert!(
        err.contains("grid `work plane`: 35 points, 6.000 m^2, maintenance factor 0.8"),
        "{err}"
    );
    assert!(
        err.contains("requirements: Em >= 1 lx: met; U0 >= 0.1: met"),
        "{err}"
    );
    assert!(
        err.contains("requirements: Em >= 1000000 lx: not met"),
        "{err}"
    );

    // The maintenance factor scales E_avg: the run's mean of the same points times 0.8.
    let res_text = std::fs::read_to_string(&res).unwrap();
    let mut rl = res_text.lines();
    let header: Vec<&str> = rl.next().unwrap().split(',').collect();
    let (ci, ei, ai) = (
        header.iter().position(|h| *h == "grid").unwrap(),
        header.iter().position(|h| *h == "E").unwrap(),
        header.iter().position(|h| *h == "area").unwrap(),
    );
    let (mut s, mut w) = (0.0, 0.0);
    for l in rl {
        let c: Vec<&str> = l.split(',').collect();
        if c[ci] == "work plane" {
            let a: f64 = c[ai].parse().unwrap();
            s += a * c[ei].parse::<f64>().unwrap();
            w += a;
        }
    }
    assert!(
        (0.8 * s / w - e(0)).abs() < 1e-9 * e(0),
        "{} {}",
        0.8 * s / w,
        e(0)
    );

    // Same seed, other thread counts: the same figures, byte for byte.
    for threads in ["1", "3"] {
        let again = dir.path().join(format!("f{threads}.csv"));
        lumest()
            .args([
                "illuminance",
                "--chains",
                "16384",
                "--quiet",
                "--threads",
                threads,
                "--scene",
            ])
            .arg(&scene)
            .arg("--points")
            .arg(&points)
            .arg("--out")
            .arg(dir.path().join(format!("e{threads}.csv")))
            .arg("--figures-out")
            .arg(&again)
            .assert()
            .success();
        assert_eq!(
            std::fs::read(&again).unwrap(),
            f.as_bytes(),
            "--threads {threads}"
        );
    }

    // --figures-out needs a grid column.
    let plain = dir.path().join("plain.csv");
    std::fs::write(&plain, "x,y,z,nx,ny,nz\n1,1,0.8,0,0,1\n").unwrap();
    let out = illuminance(
        "1000",
        &scene,
        &plain,
        &dir.path().join("x.csv"),
        &["--figures-out".as_ref(), dir.path().join("y.csv").as_ref()],
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no `grid` column"));
    // A bad area weight names the file, line and field.
    std::fs::write(
        &plain,
        "grid,area,x,y,z,nx,ny,nz\na,0.5,1,1,0.8,0,0,1\na,-1,2,1,0.8,0,0,1\n",
    )
    .unwrap();
    let out = illuminance("1000", &scene, &plain, &dir.path().join("x.csv"), &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("plain.csv:3: field `area`"), "{err}");
}

/// `lumest grid --out` onto a file the scene names (a mesh) is refused and
/// leaves it as it was: the scene's own file was the only one checked, and
/// `--out pendant.ies` replaced the luminaire with the points.
#[test]
fn grid_never_writes_over_a_file_the_scene_names() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 1 1 0\nv 2 1 0\nv 1 2 0\nv 1 1 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::fs::write(dir.path().join("m.obj"), obj).unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        format!(
            "{SCENE}\n[[surface]]\ntype = \"mesh\"\nname = \"block\"\nfile = \"m.obj\"\n\
             material = {{ type = \"lambertian\", reflectance = 0.5 }}\n"
        ),
    )
    .unwrap();
    let out = lumest()
        .args(["grid", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(dir.path().join("m.obj"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains("would overwrite the input"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("m.obj")).unwrap(),
        obj
    );
}

/// A semicylindrical grid gets its isolux plot: its normal columns hold
/// the facing direction, which was taken for the plane's normal ("the
/// points do not lie in one plane", no plot).
#[test]
fn semicylindrical_grids_get_an_isolux_plot() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, points) = grid_points(
        dir.path(),
        &format!(
            "{SCENE}\n[[grid]]\nname = \"faces\"\nsurface = \"room.z_min\"\noffset = 1.5\n\
             spacing = 0.5\nreceiver = \"semicylindrical\"\nfacing = [1, 1, 0]\n"
        ),
        "faces",
    );
    let iso = dir.path().join("iso");
    std::fs::create_dir(&iso).unwrap();
    let out = lumest()
        .args(["illuminance", "--chains", "4096", "--scene"])
        .arg(&scene)
        .arg("--points")
        .arg(&points)
        .arg("--out")
        .arg(dir.path().join("e.csv"))
        .arg("--isolux-dir")
        .arg(&iso)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("no isolux plot"), "{err}");
    assert!(iso.join("isolux_1_faces.svg").exists(), "{err}");
}

/// A semicylindrical grid's `facing` of any length: 1e200 overflowed to a
/// zero normal, written without an error.
#[test]
fn semicylindrical_facing_of_any_length() {
    let dir = tempfile::tempdir().unwrap();
    let (_, points) = grid_points(
        dir.path(),
        &format!(
            "{SCENE}\n[[grid]]\nname = \"faces\"\nsurface = \"room.z_min\"\noffset = 1.5\n\
             spacing = 1\nreceiver = \"semicylindrical\"\nfacing = [1e200, 0, 0]\n"
        ),
        "faces",
    );
    let text = std::fs::read_to_string(&points).unwrap();
    let rows: Vec<&str> = text.lines().skip(1).collect();
    assert!(!rows.is_empty());
    for r in rows {
        let c: Vec<&str> = r.split(',').collect();
        assert_eq!(&c[5..8], ["1", "0", "0"], "{r}");
    }
}

/// A disc grid's area weights: the cells over the rim carry their part on
/// the disc, and the weights sum to the disc's area (each cell carried its
/// whole area: 1.74 m^2 for a disc of 1.54).
#[test]
fn disc_grid_weights_sum_to_the_disc_area() {
    let dir = tempfile::tempdir().unwrap();
    let (_, points) = grid_points(
        dir.path(),
        &format!(
            "{SCENE}\n[[surface]]\ntype = \"disc\"\nname = \"table\"\ncenter = [2, 1.5, 0.7]\n\
             normal = [0, 0, 1]\nradius = 0.8\nmaterial = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
             [[grid]]\nname = \"table\"\nsurface = \"table\"\nborder = 0.1\n"
        ),
        "table",
    );
    let text = std::fs::read_to_string(&points).unwrap();
    let areas: Vec<f64> = text
        .lines()
        .skip(1)
        .map(|r| r.split(',').nth(8).unwrap().parse().unwrap())
        .collect();
    let total: f64 = areas.iter().sum();
    let disc = std::f64::consts::PI * 0.7 * 0.7;
    assert!((total - disc).abs() < 1e-9 * disc, "{total} for {disc}");
    let cell = areas.iter().copied().fold(0.0, f64::max);
    assert!(
        areas.iter().any(|&a| a < 0.9 * cell),
        "no rim cell: {areas:?}"
    );
}

/// A grid no light reaches: its undefined figures (U0, Ud) are empty cells
/// in figures.csv, never `NaN` written as a number, and the verdict on its
/// U0 requirement is `undefined`.
#[test]
fn undefined_figures_are_empty_cells() {
    let dir = tempfile::tempdir().unwrap();
    // The light outside the room: no light reaches the work plane.
    let (scene, points) = grid_points(
        dir.path(),
        &SCENE.replace("position = [2, 1.5, 2.3]", "position = [2, 1.5, 4]"),
        "work plane",
    );
    let figs = dir.path().join("f.csv");
    let out = illuminance(
        "1024",
        &scene,
        &points,
        &dir.path().join("e.csv"),
        &["--figures-out".as_ref(), figs.as_ref()],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let f = std::fs::read_to_string(&figs).unwrap();
    assert!(!f.contains("NaN") && !f.contains("inf"), "{f}");
    let u0: Vec<&str> = f
        .lines()
        .find(|l| l.contains(",U0,"))
        .unwrap()
        .split(',')
        .collect();
    assert_eq!(u0[3], "", "{f}");
    // Its requirement U0 >= 0.1 is undefined, not "undecided" (run longer).
    assert_eq!(u0[10], "undefined", "{f}");
}

/// A cylindrical grid 1.2 m above the floor over a cabinet 1.2 m tall:
/// `lumest grid` leaves out the points on the cabinet's top (a solid
/// receiver there would be partly inside it, and the run refused the whole
/// file), says so, and the run goes through; a hemispherical grid on the
/// floor itself, every point on a surface, is refused with the way out.
#[test]
fn solid_receivers_on_a_surface_are_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let scene = format!(
        "{SCENE}\n[[surface]]\ntype = \"box\"\nname = \"cabinet\"\nmin = [0, 0, 0]\n\
         max = [1.0, 0.8, 1.2]\nnormals = \"outward\"\n\
         material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
         [[grid]]\nname = \"cyl\"\nsurface = \"room.z_min\"\noffset = 1.2\nspacing = 0.5\n\
         receiver = \"cylindrical\"\n\
         [[grid]]\nname = \"hemi\"\nsurface = \"room.z_min\"\nspacing = 0.5\n\
         receiver = \"hemispherical\"\n"
    );
    let (s, p) = (dir.path().join("s.toml"), dir.path().join("p.csv"));
    std::fs::write(&s, &scene).unwrap();
    let o = lumest()
        .args(["grid", "--name", "cyl", "--scene"])
        .arg(&s)
        .arg("--out")
        .arg(&p)
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    // 8 x 6 cells, 4 of whose centres lie over the cabinet.
    assert!(
        e.contains("grid `cyl`: 4 of its 48 points lie on a surface") && e.contains("left out"),
        "{e}"
    );
    let text = std::fs::read_to_string(&p).unwrap();
    assert_eq!(text.lines().count(), 1 + 44, "{text}");
    let o = illuminance("1024", &s, &p, &dir.path().join("e.csv"), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = lumest()
        .args(["grid", "--name", "hemi", "--scene"])
        .arg(&s)
        .arg("--out")
        .arg(dir.path().join("h.csv"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("field `receiver`: grid `hemi`: every point lies on a surface")
            && e.contains(&format!("{}:", s.display()))
            && e.contains("offset"),
        "{e}"
    );
}

/// A grid that no light reaches (the lamp switched off): U0 and Ud are
/// undefined (0 / 0), and the summary and the report say so instead of
/// printing NaN.
#[test]
fn an_unlit_grid_has_undefined_ratios_not_nan() {
    let dir = tempfile::tempdir().unwrap();
    let dark = SCENE.replace("intensity = 300", "intensity = 0");
    let (scene, points) = grid_points(dir.path(), &dark, "work plane");
    let (res, figs, report) = (
        dir.path().join("e.csv"),
        dir.path().join("f.csv"),
        dir.path().join("r.html"),
    );
    let out = illuminance(
        "2048",
        &scene,
        &points,
        &res,
        &[
            "--figures-out".as_ref(),
            figs.as_ref(),
            "--report".as_ref(),
            report.as_ref(),
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    for f in ["U0 = E_min/E_avg", "Ud = E_min/E_max"] {
        assert!(
            err.contains(&format!("{f} undefined: no light reaches the grid")),
            "{err}"
        );
    }
    let html = std::fs::read_to_string(&report).unwrap();
    for (what, text) in [("summary", err.to_string()), ("report", html.clone())] {
        assert!(!text.contains("NaN"), "{what}: {text}");
    }
    assert!(html.contains("undefined"));
}
