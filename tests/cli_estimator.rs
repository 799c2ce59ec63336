//! Options that only one estimator reads are refused for the other, not
//! ignored without a word.

use assert_cmd::Command;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

#[test]
fn backward_estimator_refuses_local_only_options() {
    for extra in [
        &["--near-radius", "0.1"][..],
        &["--near-radius", "auto"][..],
        &["--near-paths", "4"][..],
        &["--no-stratify"][..],
        &["--qmc", "owen"][..],
    ] {
        let out = lumest()
            .args([
                "illuminance",
                "--scene",
                "data/sobolev.toml",
                "--points",
                "data/sobolev_points.csv",
                "--out",
                "-",
                "--chains",
                "64",
                "--estimator",
                "backward",
                "--quiet",
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(!out.status.success(), "{extra:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains(extra[0]) && err.contains("local estimator only"),
            "{extra:?}: {err}"
        );
    }
    // Without them the backward estimator runs.
    lumest()
        .args([
            "illuminance",
            "--scene",
            "data/sobolev.toml",
            "--points",
            "data/sobolev_points.csv",
            "--out",
            "-",
            "--chains",
            "64",
            "--estimator",
            "backward",
            "--quiet",
        ])
        .assert()
        .success();
}
