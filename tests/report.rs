//! `lumest illuminance --report R.html --isolux-dir DIR`: the HTML report
//! parsed with an HTML5 parser (scraper / html5ever): every grid's figures,
//! intervals and verdicts equal the `--figures-out` CSV's, each grid has its
//! isolux plot inline and as PNG and SVG files, the luminaire table and run
//! statistics are there, and text is escaped.

use assert_cmd::Command;
use scraper::{Html, Selector};
use std::collections::HashMap;
use std::path::Path;

fn lumest() -> Command {
    Command::cargo_bin("lumest").unwrap()
}

fn sel(s: &str) -> Selector {
    Selector::parse(s).unwrap()
}

/// Rows of a CSV file as maps from column to cell.
fn csv_rows(path: &Path) -> Vec<HashMap<String, String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let headers = r.headers().unwrap().clone();
    r.records()
        .map(|rec| {
            let rec = rec.unwrap();
            headers
                .iter()
                .zip(rec.iter())
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

/// Run `lumest grid` and `lumest illuminance` with the report on `scene`;
/// returns the parsed report and the figures CSV's rows.
fn run(dir: &Path, scene: &Path, extra: &[&str]) -> (Html, Vec<HashMap<String, String>>, String) {
    let points = dir.join("grids.csv");
    let out = lumest()
        .args(["grid", "--scene"])
        .arg(scene)
        .arg("--out")
        .arg(&points)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let (report, figures) = (dir.join("report.html"), dir.join("figures.csv"));
    let out = lumest()
        .args(["illuminance", "--scene"])
        .arg(scene)
        .arg("--points")
        .arg(&points)
        .arg("--out")
        .arg(dir.join("E.csv"))
        .arg("--figures-out")
        .arg(&figures)
        .arg("--report")
        .arg(&report)
        .arg("--isolux-dir")
        .arg(dir)
        .args(extra)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{err}");
    let html = std::fs::read_to_string(&report).unwrap();
    (Html::parse_document(&html), csv_rows(&figures), err)
}

/// Every figure of every grid in the CSV appears in the report with the
/// same value, standard error, interval and verdict; every grid has its
/// plot inline and in its two files.
fn check_grids(doc: &Html, figures: &[HashMap<String, String>], dir: &Path) {
    let grids: Vec<String> = {
        let mut g: Vec<String> = figures.iter().map(|r| r["grid"].clone()).collect();
        g.dedup();
        g
    };
    let sections: Vec<_> = doc.select(&sel("section.grid")).collect();
    assert_eq!(sections.len(), grids.len());
    for (k, (section, name)) in sections.iter().zip(&grids).enumerate() {
        assert_eq!(section.value().attr("data-grid"), Some(name.as_str()));
        for row in figures.iter().filter(|r| &r["grid"] == name) {
            let tr = section
                .select(&sel(&format!("tr[data-figure=\"{}\"]", row["figure"])))
                .next()
                .unwrap_or_else(|| panic!("grid {name}: no row {}", row["figure"]));
            for (class, col) in [
                ("value", "value"),
                ("std-error", "std_error"),
                ("ci95-low", "ci95_low"),
                ("ci95-high", "ci95_high"),
            ] {
                let cell = tr.select(&sel(&format!(".{class}"))).next().unwrap();
                assert_eq!(
                    cell.value().attr("data-value"),
                    Some(row[col].as_str()),
                    "grid {name}, {} {col}",
                    row["figure"]
                );
                // The shown text is the value rounded (2 significant
                // digits for the standard error, 4 or 5 for the others).
                let shown: f64 = cell.text().collect::<String>().trim().parse().unwrap();
                let full: f64 = row[col].parse().unwrap();
                let tol = if class == "std-error" { 0.05 } else { 5e-4 };
                assert!(
                    (shown - full).abs() <= tol * full.abs() + 1e-300,
                    "{shown} vs {full}"
                );
            }
            let verdict = tr.select(&sel("td.verdict")).next().unwrap();
            assert_eq!(verdict.text().collect::<String>(), row["verdict"]);
            if !row["verdict"].is_empty() {
                let what = if row["figure"] == "E_avg" { "Em" } else { "U0" };
                let span = section
                    .select(&sel("span.verdict"))
                    .find(|s| {
                        s.value()
                            .attr("data-requirement")
                            .is_some_and(|r| r.starts_with(what))
                    })
                    .unwrap_or_else(|| panic!("grid {name}: no {what} verdict"));
                assert!(span.value().has_class(
                    &row["verdict"].replace(' ', "-"),
                    scraper::CaseSensitivity::CaseSensitive
                ));
                let b: String = span.select(&sel("b")).next().unwrap().text().collect();
                assert_eq!(b, row["verdict"]);
            }
        }
        // The plot: inline SVG with the scale's label and isolux lines.
        let svg = section
            .select(&sel("figure.isolux svg"))
            .next()
            .unwrap_or_else(|| panic!("grid {name}: no plot"));
        let texts: Vec<String> = svg
            .select(&sel("text"))
            .map(|t| t.text().collect::<String>().trim().to_string())
            .collect();
        assert!(texts.iter().any(|t| t == "E [lx]"), "{texts:?}");
        assert!(svg.select(&sel("polyline")).count() > 0);
        let slug: String = name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let base = dir.join(format!("isolux_{}_{slug}", k + 1));
        let png = image::open(base.with_extension("png")).unwrap();
        assert!(png.width() >= 900 && png.height() >= 300);
        let svg_file = std::fs::read_to_string(base.with_extension("svg")).unwrap();
        assert!(svg_file.starts_with("<svg") && svg_file.contains("E [lx]"));
    }
}

/// The README's office compliance example, shortened to 16,384 chains.
#[test]
fn office_report_matches_its_figures() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/office.toml");
    let (doc, figures, err) = run(dir.path(), &scene, &["--chains", "16384", "--seed", "7"]);
    assert_eq!(figures.len(), 40, "eight grids, five figures each");
    // The east wall's verdicts say they leave out its 12 points behind the
    // whiteboard (flagged `enclosed`), and over how many they judge.
    let east = figures.iter().find(|r| r["grid"] == "east wall").unwrap();
    let (used, out) = (&east["points"], &east["left_out"]);
    assert_eq!(out, "12");
    let total = used.parse::<usize>().unwrap() + 12;
    assert!(
        err.contains(&format!(
            "(judged on {used} of {total} points: 12 flagged `enclosed` left out)"
        )),
        "{err}"
    );
    check_grids(&doc, &figures, dir.path());
    // Luminaires: five downlights and the pendant dimmed to 3000 lm in the scene file.
    let rows: Vec<Vec<String>> = doc
        .select(&sel("#luminaires-table tr"))
        .skip(1)
        .map(|tr| {
            tr.select(&sel("td"))
                .map(|td| td.text().collect())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 6 + 1);
    // The reference UGR (4H x 8H, 70/50/20, crosswise / endwise) of each
    // file at its flux in the scene, from the table code on the file read
    // here: the pendant dimmed to 3000 lm (rotationally symmetric, so the
    // two views agree), the downlight at its own flux.
    let reference = |file: &str, flux: Option<f64>| {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("data")
            .join(file);
        let p = lumest::io::photometry::read(&path).unwrap();
        let g = lumest::light::Goniometric::new(&p, 1.0);
        let g = match flux {
            Some(f) => lumest::light::Goniometric::new(&p, f / g.power()),
            None => g,
        };
        let area = lumest::glare::LuminousArea::of_file(&p.opening).unwrap();
        let (c, e) = lumest::glare::tabular::reference_ugr(&g, &area);
        format!("{c:.1} / {e:.1}")
    };
    let pendant = reference("pendant.ies", Some(3000.0));
    assert_eq!(
        rows[5],
        ["pendant", "ies", "3000.0", "pendant.ies", &pendant]
    );
    let downlight = reference("downlight.ldt", None);
    assert!(
        rows[..5]
            .iter()
            .all(|r| r[1] == "ldt" && r[3] == "downlight.ldt" && r[4] == downlight),
        "{rows:?} vs {downlight}"
    );
    eprintln!("reference UGR: pendant {pendant}, downlight {downlight}");
    // Run statistics: chains and seed as asked.
    let run: HashMap<String, String> = doc
        .select(&sel("#run-table tr"))
        .map(|tr| {
            (
                tr.select(&sel("th")).next().unwrap().text().collect(),
                tr.select(&sel("td")).next().unwrap().text().collect(),
            )
        })
        .collect();
    assert_eq!(run["seed"], "7");
    assert_eq!(run["chains"], "16384");
    assert_eq!(run["receivers"], "566");
    // Flags: either all pass or a table of counts.
    assert!(doc.select(&sel("#flags-ok")).count() + doc.select(&sel("#flags-table")).count() == 1);
}

/// A grid name with markup is escaped everywhere; without `--isolux-dir`
/// the report still has the plot inline; a scattered points list gets no
/// plot and says why.
#[test]
fn text_is_escaped_and_odd_grids_are_explained() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    std::fs::write(
        &scene,
        r#"[[surface]]
type = "box"
name = "room"
min = [0, 0, 0]
max = [4, 3, 2.5]
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
type = "point"
name = "lamp <i>1</i>"
position = [2, 1.5, 2.3]
intensity = 300

[[grid]]
name = "desk <b>&\"1\""
corner = [0.5, 0.5, 0.8]
edge1 = [3, 0, 0]
edge2 = [0, 2, 0]
em = 1
"#,
    )
    .unwrap();
    let (doc, figures, _) = run(dir.path(), &scene, &["--chains", "8192"]);
    check_grids(&doc, &figures, dir.path());
    assert_eq!(
        doc.select(&sel("b"))
            .filter(|b| b.text().any(|t| t == "\"1\""))
            .count(),
        0
    );
    assert_eq!(
        doc.select(&sel("section.grid i, #luminaires-table i"))
            .count(),
        0
    );
    let section = doc.select(&sel("section.grid")).next().unwrap();
    assert_eq!(section.value().attr("data-grid"), Some("desk <b>&\"1\""));
    // Scattered points of one grid: no lattice, no plot, a note.
    let points = dir.path().join("scattered.csv");
    std::fs::write(
        &points,
        "x,y,z,nx,ny,nz,grid\n1,1,0.8,0,0,1,g\n1.3,2.1,0.8,0,0,1,g\n2.7,1.4,0.8,0,0,1,g\n3.1,2.6,0.8,0,0,1,g\n0.4,0.9,0.8,0,0,1,g\n",
    )
    .unwrap();
    let report = dir.path().join("r2.html");
    let out = lumest()
        .args(["illuminance", "--scene"])
        .arg(&scene)
        .arg("--points")
        .arg(&points)
        .arg("--out")
        .arg(dir.path().join("E2.csv"))
        .arg("--report")
        .arg(&report)
        .args(["--chains", "4096"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc = Html::parse_document(&std::fs::read_to_string(&report).unwrap());
    assert_eq!(doc.select(&sel("figure.isolux")).count(), 0);
    let note: String = doc
        .select(&sel("section.grid p.note"))
        .flat_map(|p| p.text())
        .collect();
    assert!(
        note.contains("No isolux plot") && note.contains("rows and columns"),
        "{note}"
    );
    // A missing plot folder and a report over an input are refused before the run.
    let out = lumest()
        .args(["illuminance", "--scene"])
        .arg(&scene)
        .arg("--points")
        .arg(&points)
        .arg("--out")
        .arg(dir.path().join("E3.csv"))
        .arg("--isolux-dir")
        .arg(dir.path().join("nowhere"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not an existing folder"));
    let out = lumest()
        .args(["illuminance", "--scene"])
        .arg(&scene)
        .arg("--points")
        .arg(&points)
        .arg("--out")
        .arg(dir.path().join("E3.csv"))
        .arg("--report")
        .arg(&points)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert_eq!(std::fs::read_to_string(&points).unwrap().lines().count(), 6);
}

/// The road example (data/road.toml): the EN 13201-3 field has 10 rows of
/// 6 points, the class P4 verdict is in the report, and with nothing above
/// the road its illuminance is the exact direct light (no reflected part,
/// zero error), so its E_avg is the plain area-weighted average of the
/// points times the maintenance factor.
#[test]
fn road_example_report() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/road.toml");
    let (doc, figures, _) = run(dir.path(), &scene, &["--chains", "8192"]);
    check_grids(&doc, &figures, dir.path());
    let e = csv_rows(&dir.path().join("E.csv"));
    assert_eq!(e.len(), 60);
    assert!(
        e.iter()
            .all(|r| r["E_indirect"] == "0" && r["E_stderr"] == "0")
    );
    let avg = 0.8
        * e.iter()
            .map(|r| r["E"].parse::<f64>().unwrap())
            .sum::<f64>()
        / 60.0;
    let row = figures.iter().find(|r| r["figure"] == "E_avg").unwrap();
    let got: f64 = row["value"].parse().unwrap();
    assert!((got - avg).abs() < 1e-12 * avg, "{got} vs {avg}");
    assert_eq!(row["required"], "5");
    assert_eq!(row["verdict"], "met");
}
