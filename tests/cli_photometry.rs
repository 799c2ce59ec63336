//! `lumest photometry`: the summary of the seed's pendant against the
//! numbers of its file, the polar plot, and a clear error for a bad file.

use assert_cmd::Command;

#[test]
fn pendant_summary_plot_and_errors() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("polar.svg");
    let out = Command::cargo_bin("lumest")
        .unwrap()
        .args([
            "photometry",
            "data/pendant.ies",
            "--plot",
            svg.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // 879.2 cd at the nadir, 1171.1 cd at gamma = 17.5 deg (the file's
    // largest value), 8289 lamp lumens; one C-plane: rotational symmetry.
    for want in [
        "IES LM-63-1995",
        "symmetry Rotational",
        "lamps 8289 lm",
        "max intensity 1171.1 cd at C = 0 deg, gamma = 17.5 deg",
    ] {
        assert!(text.contains(want), "missing `{want}` in:\n{text}");
    }
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("C0-C180"));
    // A file cut short: the error names the file, the line and the field.
    let bad = dir.path().join("cut.ies");
    let pendant = std::fs::read_to_string("data/pendant.ies").unwrap();
    std::fs::write(&bad, &pendant[..pendant.len() / 2]).unwrap();
    let out = Command::cargo_bin("lumest")
        .unwrap()
        .args(["photometry", bad.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cut.ies:") && err.contains("candela value"),
        "{err}"
    );
}
