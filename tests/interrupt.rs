//! Ctrl-C keeps what was computed (issue 12 item 13): a SIGINT during a long
//! run stops it after the batches in hand and writes their results
//! atomically, with error bars and a note; nothing is lost.

#[cfg(unix)]
#[test]
fn sigint_writes_the_results_so_far() {
    interrupted_run_keeps_its_results(1);
}

/// GNU `timeout -s INT` signals the child and then its process group, and
/// launchers forward signals to every process: two SIGINTs in quick
/// succession are one interrupt, not a user's second Ctrl-C that ends the
/// process with nothing written.
#[cfg(unix)]
#[test]
fn a_repeated_sigint_is_one_interrupt() {
    interrupted_run_keeps_its_results(2);
}

/// Run the office on its grid, send `signals` SIGINTs back to back after
/// 4 s (one `kill` after the other, as `timeout` does; the build before
/// the grace period lost 3 runs of 3 so), and check that the results so
/// far are written.
#[cfg(unix)]
fn interrupted_run_keeps_its_results(signals: usize) {
    use std::process::{Command, Stdio};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("E.csv");
    let child = Command::new(env!("CARGO_BIN_EXE_lumest"))
        .args([
            "illuminance",
            "--scene",
            "data/office.toml",
            "--points",
            "data/office_grid.csv",
            "--out",
            out.to_str().unwrap(),
            "--time",
            "120",
            "--quiet",
        ])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Long enough for a few batches on a loaded machine.
    std::thread::sleep(std::time::Duration::from_secs(4));
    for _ in 0..signals {
        let status = Command::new("kill")
            .args(["-INT", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    }
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    // Interrupted: the results so far are written, the status says so.
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted by a signal"), "{err}");
    let text = std::fs::read_to_string(&out).unwrap();
    // The header and the 66 grid points, every one with a number and an error.
    assert_eq!(text.lines().count(), 67, "{text}");
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let e: f64 = cells[6].parse().unwrap();
        let se: f64 = cells[7].parse().unwrap();
        assert!(e > 0.0 && se > 0.0 && se < e, "{line}");
    }
}
