//! `mpirun -np 2 lumest illuminance ... --mpi` gives the single process's
//! CSV byte for byte (issue 15 item 5b), also with `--rel-error` planned
//! across ranks. Built and run only with `--features mpi` (`.ci/run`
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
    for (stop, value) in [("--chains", "60000"), ("--rel-error", "4e-3")] {
        let one = dir.path().join("one.csv");
        let two = dir.path().join("two.csv");
        let base = |out: &std::path::Path| {
            vec![
                "illuminance".to_string(),
                "--scene".into(),
                data("office.toml"),
                "--points".into(),
                data("office_grid.csv"),
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
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
