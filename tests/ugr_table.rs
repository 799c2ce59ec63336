//! `lumest ugr-table`: the printed table and the CSV carry the tabular
//! method's ratings (checked against `lumest glare` in `tests/glare.rs`),
//! crosswise and endwise in the right columns; bad inputs are refused by
//! name.

use assert_cmd::Command;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

fn data(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name)
}

#[test]
fn csv_rows_are_the_tabular_ratings() {
    use lumest::glare::tabular::{FileLuminaire, StandardRoom, View};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.csv");
    let file = data("data/photometry/sym_quadrant.ies");
    let printed = lumest()
        .arg("ugr-table")
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let printed = String::from_utf8(printed).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 20);
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(header[..3], ["X_H", "Y_H", "crosswise_70_50_20"]);
    assert_eq!(header[7], "endwise_70_50_20");
    assert_eq!(header[11], "endwise_30_30_20");
    // The 4H x 4H room (X across, Y along), by the library's own rating.
    let row: Vec<&str> = lines[9].split(',').collect();
    assert_eq!(row[..2], ["4", "4"]);
    let p = lumest::io::photometry::read(&file).unwrap();
    let g = lumest::light::Goniometric::new(&p, 1.0);
    let area = lumest::glare::LuminousArea::of_file(&p.opening).unwrap();
    for (view, col) in [(View::Crosswise, 2), (View::Endwise, 7)] {
        let room = StandardRoom {
            across: 8.0,
            along: 8.0,
            eye: 0.0,
            h: 2.0,
            spacing: 0.5,
            rho: [0.7, 0.5, 0.2],
        };
        let lum = FileLuminaire {
            dist: &g,
            area: &area,
            frame: view.frame(),
        };
        let want = room.rating(&lum).ugr;
        assert_eq!(row[col], format!("{want:.2}"), "{view:?}");
    }
    // The 2H x 12H room's printed line carries the CSV's values to 1
    // decimal (both rounded from the full rating: within 0.05 + 0.005).
    let csv: Vec<f64> = lines[6]
        .split(',')
        .skip(2)
        .map(|v| v.parse().unwrap())
        .collect();
    let line = printed.lines().find(|l| l.starts_with("2H 12H")).unwrap();
    let got: Vec<f64> = line[10..]
        .split([' ', '|'])
        .filter(|s| !s.is_empty())
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(got.len(), 10);
    for (a, b) in got.iter().zip(&csv) {
        assert!((a - b).abs() <= 0.0551, "{got:?} vs {csv:?}");
    }
    assert!(printed.contains("luminaire flux 3139.6 lm"));
}

#[test]
fn bad_inputs_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let refuse = |args: &[&std::ffi::OsStr], what: &str| {
        let out = lumest().arg("ugr-table").args(args).assert().failure();
        let err = String::from_utf8_lossy(&out.get_output().stderr).to_string();
        assert!(err.contains(what), "{err}");
    };
    let b = data("data/photometry/type_b.ies");
    refuse(&[b.as_os_str()], "type B photometry");
    // No luminous opening: no luminance.
    let point = dir.path().join("point.ies");
    std::fs::write(
        &point,
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 3 1 1 2 0 0 0\n1 1 0\n0 45 90\n0\n100 70 0\n",
    )
    .unwrap();
    refuse(&[point.as_os_str()], "no luminous area");
    let q = data("data/photometry/sym_quadrant.ies");
    refuse(
        &[q.as_os_str(), "--spacing".as_ref(), "0".as_ref()],
        "--spacing 0",
    );
    // A grid of 1 / spacing^2 luminaires: 0.001 H would need gigabytes.
    refuse(
        &[q.as_os_str(), "--spacing".as_ref(), "0.001".as_ref()],
        "--spacing 0.001",
    );
    // All the light upwards: no luminance towards the eye, no rating (the
    // table would be NaN throughout).
    let up = dir.path().join("up.ies");
    std::fs::write(
        &up,
        "IESNA:LM-63-2002\nTILT=NONE\n1 -1 1 5 1 1 2 0.3 0.3 0\n1 1 0\n0 45 90 135 180\n0\n0 0 0 100 100\n",
    )
    .unwrap();
    refuse(
        &[up.as_os_str()],
        "no finite UGR for the 2H x 2H room viewed crosswise, reflectances 70/50/20",
    );
    refuse(
        &[q.as_os_str(), "--spacing".as_ref(), "nan".as_ref()],
        "--spacing NaN",
    );
    // The output may not be the input.
    let copy = dir.path().join("q.ies");
    std::fs::copy(&q, &copy).unwrap();
    refuse(
        &[copy.as_os_str(), "--out".as_ref(), copy.as_os_str()],
        "--out",
    );
    assert_eq!(std::fs::read(&copy).unwrap(), std::fs::read(&q).unwrap());
}
