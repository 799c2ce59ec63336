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
