//! `mpirun -np 2 lumest illuminance ... --mpi` gives the single process's
//! CSV byte for byte (issue 15 item 5b), also with `--rel-error` and
//! `--rms-error`, whose batches the ranks grow together. Built and run only with `--features mpi` (`.ci/run`
//! installs OpenMPI and runs it).
#![cfg(feature = "mpi")]

use std::process::Command;

fn data(f: &str) -> String {
    format!("{}/data/{f}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn mpirun_two_ranks_give_the_single_process_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let bin = env!("CARGO_BIN_EXE_lumest");
    // A 20 x 20 grid on the Sobolev plane, at an RMS target: the ranks
    // grow their batches together, as for `--rel-error` on the office.
    let grid = dir.path().join("grid.csv");
    let mut text = String::from("x,y,z,nx,ny,nz\n");
    for i in 0..20 {
        for j in 0..20 {
            let (x, y) = (-3.0 + 0.3 * (i as f64 + 0.5), -3.0 + 0.3 * (j as f64 + 0.5));
            text += &format!("{x},{y},0,0,0,1\n");
        }
    }
    std::fs::write(&grid, text).unwrap();
    let grid = grid.to_string_lossy().into_owned();
    for (scene, points, stop, value) in [
        (
            data("office.toml"),
            data("office_grid.csv"),
            "--chains",
            "60000",
        ),
        (
            data("office.toml"),
            data("office_grid.csv"),
            "--rel-error",
            "4e-3",
        ),
        (data("sobolev.toml"), grid.clone(), "--rms-error", "3e-3"),
    ] {
        let one = dir.path().join("one.csv");
        let two = dir.path().join("two.csv");
        let base = |out: &std::path::Path| {
            vec![
                "illuminance".to_string(),
                "--scene".into(),
                scene.clone(),
                "--points".into(),
                points.clone(),
                stop.into(),
                value.into(),
                "--seed".into(),
                "4".into(),
                "--quiet".into(),
                "--out".into(),
                out.to_string_lossy().into_owned(),
            ]
        };
        let o = Command::new(bin).args(base(&one)).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        if stop != "--chains" {
            // The ranks below grow their batches together, exchanging the
            // parts at every stage.
            assert!(err.contains("batches grew in"), "{err}");
        }
        let mut args = vec![
            "--allow-run-as-root".to_string(),
            "--oversubscribe".into(),
            "-np".into(),
            "2".into(),
            bin.into(),
        ];
        args.extend(base(&two));
        args.push("--mpi".into());
        let o = Command::new("mpirun")
            .args(&args)
            .output()
            .expect("mpirun on the PATH");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert!(err.contains("2 MPI rank(s)"), "{err}");
        let (a, b) = (std::fs::read(&one).unwrap(), std::fs::read(&two).unwrap());
        assert!(
            a.len() > 1000 && a == b,
            "{stop}: 2 ranks differ from 1 process"
        );
    }
}

/// An output that rank 0 refuses (here the points file itself) stops every
/// rank with rank 0's message, rather than leaving the others waiting in
/// the gather (`timeout` ends a hang with status 124).
#[test]
fn a_refused_output_stops_every_rank() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("points.csv");
    std::fs::copy(data("office_grid.csv"), &points).unwrap();
    let before = std::fs::read(&points).unwrap();
    let points = points.to_string_lossy().into_owned();
    let o = Command::new("timeout")
        .args([
            "120",
            "mpirun",
            "--allow-run-as-root",
            "--oversubscribe",
            "-np",
            "2",
            env!("CARGO_BIN_EXE_lumest"),
            "illuminance",
            "--scene",
            &data("office.toml"),
            "--points",
            &points,
            "--chains",
            "10000",
            "--quiet",
            "--out",
            &points,
            "--mpi",
        ])
        .output()
        .expect("timeout and mpirun on the PATH");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(124), "the ranks hung: {err}");
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("--out"), "{err}");
    assert_eq!(
        std::fs::read(&points).unwrap(),
        before,
        "the input was overwritten"
    );
}
