//! The `receiver` column of the points CSV: each row's receiver type
//! (`planar` when absent or empty), and clear errors naming the file, the
//! line and the field.

use assert_cmd::Command;
use std::f64::consts::PI;

/// A point source of 400 cd 2 m above a black floor: every value is the
/// exact direct term.
const SCENE: &str = r#"[[surface]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]
material = { type = "lambertian", reflectance = 0.0 }

[[light]]
type = "point"
position = [0, 0, 3]
intensity = 400
"#;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

/// Run on `points` (CSV text); `Ok(output CSV)` or `Err(stderr)`.
fn run(points: &str) -> Result<String, String> {
    run_with_log(points).map(|(out, _)| out)
}

/// Run on `points`; `Ok((output CSV, stderr))` or `Err(stderr)`.
fn run_with_log(points: &str) -> Result<(String, String), String> {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let pts = dir.path().join("p.csv");
    std::fs::write(&pts, points).unwrap();
    let res = dir.path().join("r.csv");
    let out = lumest()
        .args(["illuminance", "--chains", "2048", "--quiet", "--scene"])
        .arg(&scene)
        .arg("--points")
        .arg(&pts)
        .arg("--out")
        .arg(&res)
        .output()
        .unwrap();
    if out.status.success() {
        Ok((
            std::fs::read_to_string(&res).unwrap(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        ))
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

#[test]
fn each_row_reads_its_receiver_type() {
    // The light 2 m above and 2 m aside: e = 45 degrees, straight ahead of
    // the half cylinder facing -x.
    let text = run("id,x,y,z,nx,ny,nz,receiver\n\
                    h,2,0,1,0,0,1,planar\n\
                    d,2,0,1,0,0,1,\n\
                    z,2,0,1,0,0,1,cylindrical\n\
                    sz,2,0,1,-1,0,0,semicylindrical\n\
                    hs,2,0,1,0,0,1,hemispherical\n\
                    o,2,0,1,0,0,1,spherical\n")
    .unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let e_col = head.iter().position(|h| *h == "E").expect("an E column");
    let e: Vec<f64> = lines
        .map(|l| l.split(',').nth(e_col).unwrap().parse().unwrap())
        .collect();
    let (i, h, c, s) = (400.0, 2.0, 0.5f64.sqrt(), 0.5f64.sqrt());
    let k = i / (h * h);
    let want = [
        k * c.powi(3),
        k * c.powi(3),
        k * c * c * s / PI,
        k * 2.0 * c * c * s / PI,
        k * (1.0 + c) * c * c / 4.0,
        k * c * c / 4.0,
    ];
    for (got, want) in e.iter().zip(want) {
        // Written with 6 significant digits at least.
        assert!((got / want - 1.0).abs() < 1e-5, "{got} vs {want}");
    }
}

#[test]
fn bad_receivers_name_file_line_and_field() {
    let err =
        run("x,y,z,nx,ny,nz,receiver\n1,0,1,0,0,1,planar\n1,0,1,0,0,1,cylinder\n").unwrap_err();
    assert!(
        err.contains("p.csv:3") && err.contains("receiver") && err.contains("cylindrical"),
        "{err}"
    );
    let err = run("x,y,z,nx,ny,nz,receiver\n1,0,1,0,0,1,semicylindrical\n").unwrap_err();
    assert!(
        err.contains("p.csv:2") && err.contains("horizontal"),
        "{err}"
    );
    // A solid receiver on the floor would be half inside it.
    let err = run("x,y,z,nx,ny,nz,receiver\n1,0,0,0,0,1,spherical\n").unwrap_err();
    assert!(
        err.contains("p.csv:2") && err.contains("on a surface"),
        "{err}"
    );
    // A planar point on the floor is fine.
    assert!(run("x,y,z,nx,ny,nz,receiver\n1,0,0,0,0,1,planar\n").is_ok());
}

#[test]
fn modelling_ratio_of_points_listed_planar_and_cylindrical() {
    // e = 45 degrees: E_z / E_h = sin e / (pi cos e) = 1 / pi, exact (black floor).
    let (csv, log) = run_with_log(
        "id,x,y,z,nx,ny,nz,receiver\n\
         h,2,0,1,0,0,1,planar\n\
         z,2,0,1,0,0,1,cylindrical\n\
         other,1,0,1,0,0,1,cylindrical\n",
    )
    .unwrap();
    // The CSV's columns: the ratio on the pair's cylindrical row, empty on
    // the others.
    let mut rows = csv.lines().map(|l| l.split(',').collect::<Vec<_>>());
    let head = rows.next().unwrap();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let (cr, cs) = (col("modelling_ratio"), col("modelling_ratio_stderr"));
    assert_eq!(cs, cr + 1);
    let rows: Vec<Vec<&str>> = rows.collect();
    let ratio: f64 = rows[1][cr].parse().unwrap();
    assert!((ratio - 1.0 / PI).abs() < 1e-12, "{ratio}");
    assert_eq!(rows[1][cs], "0");
    for k in [0, 2] {
        assert_eq!((rows[k][cr], rows[k][cs]), ("", ""), "row {k}");
    }
    // The ratio is the row's E over the planar row's: a moved light would
    // change both.
    let e = |k: usize| rows[k][col("E")].parse::<f64>().unwrap();
    assert!((ratio - e(1) / e(0)).abs() < 1e-12);
    assert!(
        log.contains("modelling E_z/E_h") && log.contains("at 1 point(s)"),
        "{log}"
    );
    let want = format!("p.csv:2+3: {:.4} +- 0.0000", 1.0 / PI);
    assert!(log.contains(&want), "{want} not in {log}");
    // No average over mixed receiver types.
    assert!(
        log.contains("mixed receiver types (cylindrical, planar)")
            && !log.contains("uniformity U0"),
        "{log}"
    );
    // No pair, no line.
    let (csv, log) = run_with_log("x,y,z,nx,ny,nz,receiver\n2,0,1,0,0,1,cylindrical\n").unwrap();
    assert!(!log.contains("modelling"), "{log}");
    assert!(!csv.contains("modelling"), "{csv}");
    // A pair under the floor gets no light: the ratio is undefined, and
    // written so (not 0, not an empty cell).
    let (csv, log) =
        run_with_log("x,y,z,nx,ny,nz,receiver\n2,0,-1,0,0,1,planar\n2,0,-1,0,0,1,cylindrical\n")
            .unwrap();
    assert!(log.contains("undefined (E_h = 0"), "{log}");
    let row: Vec<&str> = csv.lines().nth(2).unwrap().split(',').collect();
    assert_eq!(&row[row.len() - 2..], ["NaN", "NaN"], "{csv}");
}
