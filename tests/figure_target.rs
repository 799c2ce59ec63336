//! `lumest illuminance --figure-target GRID:FIGURE:H`: a run planned for a
//! grid figure's precision (the two-stage pilot rule of `--rel-error`).

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
"#;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

/// The figure's interval half-width in a figures CSV.
fn half_width(figs: &str, grid: &str, figure: &str) -> (f64, usize) {
    let text = std::fs::read_to_string(figs).unwrap();
    let mut lines = text.lines();
    let h: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| h.iter().position(|x| *x == n).unwrap();
    for l in lines {
        let r: Vec<&str> = l.split(',').collect();
        if r[col("grid")] == grid && r[col("figure")] == figure {
            let lo: f64 = r[col("ci95_low")].parse().unwrap();
            let hi: f64 = r[col("ci95_high")].parse().unwrap();
            return (0.5 * (hi - lo), r[col("batches")].parse().unwrap());
        }
    }
    panic!("no {grid} {figure} in {text}");
}

/// Runs `illuminance` with `extra` options; returns stderr.
fn run(dir: &std::path::Path, extra: &[&str], out: &str, figs: &str) -> String {
    let o = lumest()
        .args(["illuminance", "--quiet", "--threads", "2", "--scene"])
        .arg(dir.join("s.toml"))
        .arg("--points")
        .arg(dir.join("p.csv"))
        .arg("--out")
        .arg(dir.join(out))
        .arg("--figures-out")
        .arg(dir.join(figs))
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    err
}

/// The plan reaches the target where the 32-batch minimum does not; its
/// result is that of a `--chains` run of the planned size, bit for bit; a
/// target half as wide plans about four times the batches.
#[test]
fn a_u0_target_is_planned_and_met() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    lumest()
        .args(["grid", "--scene"])
        .arg(d.join("s.toml"))
        .arg("--out")
        .arg(d.join("p.csv"))
        .assert()
        .success();
    // The batch size is fixed (`--batch-size`): the plan's own sizing of
    // batches is checked by tests/batch_plan.rs; here the batch counts of
    // the runs are compared, so they must hold the same chains.
    const BS: &str = "1024";
    // A loose target plans the minimum, 32 batches, for comparison.
    let err0 = run(
        d,
        &["--figure-target", "work plane:U0:1", "--batch-size", BS],
        "min.csv",
        "min_f.csv",
    );
    assert!(
        err0.contains("so 32 fresh batches were planned") && err0.contains("target met"),
        "{err0}"
    );
    let (h_min, b_min) = half_width(d.join("min_f.csv").to_str().unwrap(), "work plane", "U0");
    assert_eq!(b_min, 32);
    let target = h_min / 1.6;
    let spec = format!("work plane:U0:{target}");
    let err = run(
        d,
        &["--figure-target", &spec, "--batch-size", BS],
        "e.csv",
        "f.csv",
    );
    let (h, b) = half_width(d.join("f.csv").to_str().unwrap(), "work plane", "U0");
    assert!(h <= target, "half-width {h} > target {target}: {err}");
    assert!(err.contains("target met"), "{err}");
    // (h_min / target)^2 = 2.56 times the minimum's batches, or more (the margin q).
    assert!((80..8 * 32).contains(&b), "{b} batches: {err}");
    // The same bytes as a --chains run of the planned size.
    let bs: u64 = err
        .split("per batch of ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let chains = (b as u64 * bs).to_string();
    run(
        d,
        &["--chains", &chains, "--batch-size", BS],
        "c.csv",
        "cf.csv",
    );
    assert_eq!(
        std::fs::read(d.join("e.csv")).unwrap(),
        std::fs::read(d.join("c.csv")).unwrap()
    );
    // Half the width: four times the batches (the same pilot; the run
    // itself capped by --chains, which the summary says).
    let spec2 = format!("work plane:U0:{}", target / 2.0);
    let cap = (32 * bs).to_string();
    let err2 = run(
        d,
        &[
            "--figure-target",
            &spec2,
            "--chains",
            &cap,
            "--batch-size",
            BS,
        ],
        "e2.csv",
        "f2.csv",
    );
    let planned = |e: &str| -> f64 {
        e.split("so ")
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .unwrap()
            .parse()
            .unwrap()
    };
    let ratio = planned(&err2) / planned(&err);
    assert!((3.95..4.05).contains(&ratio), "{err2}\n{err}");
    assert!(
        err2.contains("(capped by --chains)") && err2.contains("target MISSED"),
        "{err2}"
    );
}

#[test]
fn bad_targets_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("s.toml"), SCENE).unwrap();
    std::fs::write(d.join("p.csv"), "x,y,z,nx,ny,nz\n1,1,0.8,0,0,1\n").unwrap();
    for (args, msg) in [
        (
            vec!["--figure-target", "work plane:U0:0.01"],
            "no `grid` column",
        ),
        (
            vec!["--figure-target", "work plane:U9:0.01"],
            "unknown figure",
        ),
        (vec!["--figure-target", "work plane:U0:0"], "positive"),
    ] {
        let o = lumest()
            .args(["illuminance", "--quiet", "--scene"])
            .arg(d.join("s.toml"))
            .arg("--points")
            .arg(d.join("p.csv"))
            .arg("--out")
            .arg(d.join("e.csv"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(msg), "{args:?}: {err}");
    }
    std::fs::write(d.join("p.csv"), "grid,x,y,z,nx,ny,nz\nwp,1,1,0.8,0,0,1\n").unwrap();
    let o = lumest()
        .args(["illuminance", "--quiet", "--scene"])
        .arg(d.join("s.toml"))
        .arg("--points")
        .arg(d.join("p.csv"))
        .arg("--out")
        .arg(d.join("e.csv"))
        .args(["--figure-target", "floor:E_avg:1", "--rel-error", "0.01"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("no grid `floor`"), "{err}");
}
