//! Inputs and outputs a user can trust: no row dropped without a word,
//! nothing overwritten, sizes checked before anything is allocated.

use assert_cmd::Command;
use std::path::Path;

const SCENE: &str = r#"[[surface]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]
material = { type = "lambertian", reflectance = 0.5 }

[[surface]]
type = "plane"
point = [0.0, 0.0, 1.0]
normal = [0.0, 0.0, -1.0]
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "point"
position = [0.0, 0.0, 0.5]
intensity = 1.0
"#;

const POINTS: &str = "id,x,y,z,nx,ny,nz\na,0,0,0,0,0,1\nb,1,0,0,0,0,1\nc,0.5,0,1,0,0,-1\n";

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

/// Run `lumest ARGS` and return (success, stderr).
fn run(args: &[&str]) -> (bool, String) {
    let o = lumest().args(args).output().unwrap();
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A row whose id starts with `#` is a row, not a comment, and the summary
/// counts the rows in and out (only lines before the header are comments).
#[test]
fn ids_starting_with_hash_are_rows_and_rows_are_counted() {
    let dir = tempfile::tempdir().unwrap();
    let s = write(dir.path(), "scene.toml", SCENE);
    let p = write(
        dir.path(),
        "p.csv",
        "# points for a test\nid,x,y,z,nx,ny,nz\n#1,0,0,0,0,0,1\n#2,1,0,0,0,0,1\nc,0.5,0,1,0,0,-1\n",
    );
    let out = dir.path().join("E.csv");
    let out_s = out.to_string_lossy().into_owned();
    let (ok, err) = run(&[
        "illuminance",
        "--scene",
        &s,
        "--points",
        &p,
        "--out",
        &out_s,
        "--chains",
        "500",
        "--quiet",
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    let ids: Vec<&str> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(ids, ["#1", "#2", "c"], "{text}");
    assert!(
        err.contains(&format!(
            "points: 3 rows read from {p} (and 1 comment line before the header), 3 rows written to {out_s}"
        )),
        "{err}"
    );
}

/// A column named twice, or named like a result column, is refused before
/// the run with the file and the column.
#[test]
fn duplicated_or_reserved_column_names_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let s = write(dir.path(), "scene.toml", SCENE);
    let out = dir.path().join("E.csv").to_string_lossy().into_owned();
    for (name, text, want) in [
        (
            "dup.csv",
            "id,x,y,z,nx,ny,nz,id\na,0,0,0,0,0,1,b\n",
            "dup.csv:1: field `id`",
        ),
        (
            "res.csv",
            "E,x,y,z,nx,ny,nz\n1,0,0,0,0,0,1\n",
            "res.csv: column `E`",
        ),
    ] {
        let p = write(dir.path(), name, text);
        let (ok, err) = run(&[
            "illuminance",
            "--scene",
            &s,
            "--points",
            &p,
            "--out",
            &out,
            "--chains",
            "500",
            "--quiet",
        ]);
        assert!(!ok && err.contains(want), "{name}: {err}");
        assert!(!Path::new(&out).exists(), "{name}: output written");
    }
    let v = write(
        dir.path(),
        "v.csv",
        "x,y,z,dx,dy,dz,L_flag\n0,0,0.5,0,0,1,a\n",
    );
    let (ok, err) = run(&[
        "luminance",
        "--scene",
        &s,
        "--views",
        &v,
        "--out",
        &out,
        "--chains",
        "500",
        "--quiet",
    ]);
    assert!(!ok && err.contains("column `L_flag`"), "{err}");
}

/// Requests too large to hold are refused before anything is allocated,
/// with the limit in the message.
#[test]
fn unbounded_requests_are_refused_with_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let s = write(dir.path(), "scene.toml", SCENE);
    let p = write(dir.path(), "p.csv", POINTS);
    let out = dir.path().join("o.csv").to_string_lossy().into_owned();
    let (ok, err) = run(&[
        "luminance",
        "--scene",
        &s,
        "--fan-at",
        "0,0,0,0,0,1",
        "--fan",
        "0.01,0.01",
        "--out",
        &out,
        "--quiet",
    ]);
    assert!(
        !ok && err.contains("9000 x 36000 = 324000000 views; at most 4000000"),
        "{err}"
    );
    let (ok, err) = run(&[
        "illuminance",
        "--scene",
        &s,
        "--points",
        &p,
        "--out",
        &out,
        "--orders",
        "4294967295",
        "--quiet",
    ]);
    assert!(!ok && err.contains("--orders must be at most 100"), "{err}");
    let (ok, err) = run(&[
        "render",
        "--scene",
        &s,
        "--eye",
        "0,0,0.5",
        "--look",
        "1,0,0.5",
        "--width",
        "4294967296",
        "--height",
        "4294967296",
        "--out",
        &out,
        "--quiet",
    ]);
    assert!(!ok && err.contains("at most 4 Mpixel"), "{err}");
    let (ok, err) = run(&[
        "render",
        "--scene",
        &s,
        "--eye",
        "0,0,0.5",
        "--look",
        "1,0,0.5",
        "--width",
        "2000",
        "--height",
        "2000",
        "--aperture",
        "0.01",
        "--lens-samples",
        "16",
        "--out",
        &out,
        "--quiet",
    ]);
    assert!(
        !ok && err.contains("64000000 views; at most 4000000"),
        "{err}"
    );
    // Products past 2^64 are refused, not wrapped to 0 and let through (a
    // panic on allocation, and a loop of 2^64 views; a reviewer's finds).
    let (ok, err) = run(&[
        "render",
        "--scene",
        &s,
        "--eye",
        "0,0,0.5",
        "--look",
        "1,0,0.5",
        "--width",
        "2",
        "--height",
        "2",
        "--aperture",
        "0.01",
        "--lens-samples",
        "4611686018427387904",
        "--out",
        &out,
        "--quiet",
    ]);
    assert!(
        !ok && err.contains("more than 2^64 views; at most 4000000"),
        "{err}"
    );
    let (ok, err) = run(&[
        "luminance",
        "--scene",
        &s,
        "--fan-at",
        "0,0,0,0,0,1",
        "--fan",
        "2.0954757928848267e-08,8.381903171539307e-08",
        "--out",
        &out,
        "--quiet",
    ]);
    assert!(
        !ok && err.contains("= more than 2^64 views; at most 4000000"),
        "{err}"
    );
    let mesh = write(
        dir.path(),
        "t.obj",
        "v 1 1 1\nv 1 -1 -1\nv -1 1 -1\nv -1 -1 1\nf 1 2 3\nf 1 4 2\nf 1 3 4\nf 2 4 3\n",
    );
    let (ok, err) = run(&["sh-fit", &mesh, "--degree", "1000", "--out", &out]);
    assert!(!ok && err.contains("--degree 1000: at most 100"), "{err}");
    let (ok, err) = run(&[
        "sh-fit",
        &mesh,
        "--degree",
        "2",
        "--samples",
        "1000000000",
        "--out",
        &out,
    ]);
    assert!(!ok && err.contains("at most 2000000"), "{err}");
    assert!(!Path::new(&out).exists());
}

/// Every output is checked before the scene is even loaded: a missing
/// folder, a folder as the output, an output over an input (however the
/// path is spelt) or over another output.
#[test]
fn outputs_are_checked_before_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_string_lossy().into_owned();
    let s = write(dir.path(), "scene.toml", SCENE);
    let p = write(dir.path(), "p.csv", POINTS);
    let v = write(dir.path(), "v.csv", "x,y,z,dx,dy,dz\n0,0,0.5,0,0,1\n");
    let base = [
        "illuminance",
        "--scene",
        &s,
        "--points",
        &p,
        "--chains",
        "500",
        "--quiet",
    ];
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["--out".into(), format!("{d}/missing/E.csv")],
            "does not exist",
        ),
        (vec!["--out".into(), d.clone()], "is a folder"),
        (
            vec!["--out".into(), format!("{d}/./p.csv")],
            "would overwrite the input",
        ),
        (
            vec![
                "--out".into(),
                format!(
                    "{d}/../{}/scene.toml",
                    dir.path().file_name().unwrap().to_string_lossy()
                ),
            ],
            "would overwrite the input",
        ),
        (
            vec![
                "--out".into(),
                format!("{d}/E.csv"),
                "--views".into(),
                v.clone(),
                "--views-out".into(),
                format!("{d}/./E.csv"),
            ],
            "--views-out",
        ),
        (
            vec![
                "--out".into(),
                "-".into(),
                "--views".into(),
                v.clone(),
                "--views-out".into(),
                "-".into(),
            ],
            "both write to standard output",
        ),
    ];
    for (extra, want) in cases {
        let mut args: Vec<&str> = base.to_vec();
        args.extend(extra.iter().map(String::as_str));
        let (ok, err) = run(&args);
        assert!(!ok && err.contains(want), "{extra:?}: {err}");
        // Refused before the scene was loaded, let alone run.
        assert!(!err.contains("lumest: scene"), "{extra:?}: {err}");
    }
    assert_eq!(std::fs::read_to_string(&p).unwrap(), POINTS);
    assert_eq!(std::fs::read_to_string(&s).unwrap(), SCENE);
    assert!(!dir.path().join("E.csv").exists());
    // The luminance and render outputs too.
    let (ok, err) = run(&[
        "luminance",
        "--scene",
        &s,
        "--views",
        &v,
        "--out",
        &v,
        "--quiet",
    ]);
    assert!(!ok && err.contains("would overwrite the input"), "{err}");
    let (ok, err) = run(&[
        "render",
        "--scene",
        &s,
        "--eye",
        "0,0,0.5",
        "--look",
        "1,0,0.5",
        "--out",
        &format!("{d}/scene"),
        "--width",
        "8",
        "--height",
        "6",
        "--chains",
        "500",
        "--quiet",
    ]);
    // `--out DIR/scene` writes DIR/scene.png, .hdr, _false.png and .csv: none is the scene file.
    assert!(ok, "{err}");
    // Existing outputs are replaced: a second run over them is no clash.
    for _ in 0..2 {
        let (ok, err) = run(&[
            "illuminance",
            "--scene",
            &s,
            "--points",
            &p,
            "--chains",
            "500",
            "--quiet",
            "--out",
            &format!("{d}/E.csv"),
            "--views",
            &v,
            "--views-out",
            &format!("{d}/L.csv"),
        ]);
        assert!(ok, "{err}");
    }
    let (ok, err) = run(&[
        "render",
        "--scene",
        &s,
        "--eye",
        "0,0,0.5",
        "--look",
        "1,0,0.5",
        "--out",
        &format!("{d}/nowhere/img.png"),
        "--quiet",
    ]);
    assert!(
        !ok && err.contains("does not exist") && !err.contains("lumest: scene"),
        "{err}"
    );
}

/// Files the scene refers to (an OBJ mesh, an SH coefficient file, an IES
/// file) are inputs too: an output over one of them is refused before the
/// run, by illuminance, luminance and render (whose `.csv` lands on the
/// coefficient file), and the files are left as they were. Before, only the
/// files named on the command line were counted.
#[test]
fn outputs_over_files_the_scene_refers_to_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_string_lossy().into_owned();
    let obj =
        "v 2 2 0.2\nv 2.2 2 0.2\nv 2 2.2 0.2\nv 2 2 0.4\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
    let coeffs = "k,m,a,b\n0,0,0.1,0\n";
    let ies = std::fs::read_to_string("data/pendant.ies").unwrap();
    write(dir.path(), "tetra.obj", obj);
    write(dir.path(), "blob.csv", coeffs);
    write(dir.path(), "lamp.ies", &ies);
    let scene = format!(
        "{SCENE}\n[[surface]]\ntype = \"mesh\"\nfile = \"tetra.obj\"\n\
         material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
         [[surface]]\ntype = \"sh\"\nfile = \"blob.csv\"\ncenter = [-2, -2, 0.5]\n\
         material = {{ type = \"lambertian\", reflectance = 0.5 }}\n\
         [[light]]\ntype = \"ies\"\nfile = \"sub/../lamp.ies\"\nposition = [3, 3, 0.9]\n"
    );
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    let s = write(dir.path(), "scene.toml", &scene);
    let p = write(dir.path(), "p.csv", POINTS);
    let v = write(dir.path(), "v.csv", "x,y,z,dx,dy,dz\n0,0,0.5,0,0,1\n");
    // The scene itself is fine: a run with an output elsewhere works.
    let good = format!("{d}/E.csv");
    let (ok, err) = run(&[
        "illuminance",
        "--scene",
        &s,
        "--points",
        &p,
        "--out",
        &good,
        "--chains",
        "500",
        "--quiet",
    ]);
    assert!(ok, "{err}");
    for target in ["tetra.obj", "blob.csv", "lamp.ies"] {
        let out = format!("{d}/{target}");
        let (ok, err) = run(&[
            "illuminance",
            "--scene",
            &s,
            "--points",
            &p,
            "--out",
            &out,
            "--chains",
            "500",
            "--quiet",
        ]);
        assert!(
            !ok && err.contains("would overwrite the input"),
            "{target}: {err}"
        );
        assert!(
            err.contains(target) && !err.contains("lumest: scene"),
            "{target}: {err}"
        );
        let (ok, err) = run(&[
            "luminance",
            "--scene",
            &s,
            "--views",
            &v,
            "--out",
            &out,
            "--chains",
            "500",
            "--quiet",
        ]);
        assert!(
            !ok && err.contains("would overwrite the input"),
            "{target}: {err}"
        );
    }
    let (ok, err) = run(&[
        "render",
        "--scene",
        &s,
        "--eye",
        "0,-1,0.5",
        "--look",
        "0,0,0.5",
        "--width",
        "4",
        "--height",
        "4",
        "--out",
        &format!("{d}/blob.png"),
        "--chains",
        "500",
        "--quiet",
    ]);
    assert!(!ok && err.contains("would overwrite the input"), "{err}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("tetra.obj")).unwrap(),
        obj
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("blob.csv")).unwrap(),
        coeffs
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("lamp.ies")).unwrap(),
        ies
    );
}

/// An output named by a symbolic link is written to the file the link
/// leads to, the link kept: renamed onto the link, the results replaced
/// the link and left its file stale, with no word (a reviewer's find).
#[cfg(unix)]
#[test]
fn an_output_through_a_link_lands_in_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let s = write(dir.path(), "scene.toml", SCENE);
    let p = write(dir.path(), "p.csv", POINTS);
    std::fs::create_dir(dir.path().join("results")).unwrap();
    let file = write(&dir.path().join("results"), "E.csv", "old\n");
    let link = dir.path().join("E_link.csv");
    std::os::unix::fs::symlink("results/E.csv", &link).unwrap();
    let (ok, err) = run(&[
        "illuminance",
        "--scene",
        &s,
        "--points",
        &p,
        "--out",
        link.to_str().unwrap(),
        "--chains",
        "500",
        "--quiet",
    ]);
    assert!(ok, "{err}");
    let meta = std::fs::symlink_metadata(&link).unwrap();
    assert!(meta.file_type().is_symlink(), "the link was replaced");
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("id,x,y,z,nx,ny,nz,E,"), "{text}");
    // Nothing left beside the file or the link.
    for d in [dir.path(), &dir.path().join("results")] {
        let stray: Vec<_> = std::fs::read_dir(d)
            .unwrap()
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
            .collect();
        assert!(stray.is_empty(), "{stray:?}");
    }
}
