//! The HTML report of a run: one self-contained page (styles inline, plots
//! as inline SVG) with the scene, the luminaires, every grid's figures with
//! their 95 % intervals and verdicts, its isolux plot, and the run's
//! statistics and flags.
//!
//! The page is a `minijinja` template (`report.html`) filled from
//! [`Report`]; every text is HTML-escaped by the template engine (auto
//! escape for `.html`), only the plots' SVG, which plotters writes with its
//! own text escaped, is inserted as is. Numbers are shown rounded and carry
//! their full value (as in the `--figures-out` CSV) in a `data-value`
//! attribute.

pub mod outline;

use serde::Serialize;

/// The report template.
const TEMPLATE: &str = include_str!("report.html");

/// Everything the report shows, as text.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// Page title.
    pub title: String,
    /// The command line of the run.
    pub command: String,
    /// The program and its version.
    pub program: String,
    /// The scene file.
    pub scene_file: String,
    /// The compiled scene's summary line.
    pub scene_summary: String,
    /// Notes on the scene (portals, lights).
    pub scene_notes: Vec<String>,
    /// The luminaires.
    pub luminaires: Vec<Luminaire>,
    /// Their total flux \[lm\].
    pub total_flux: String,
    /// The grids.
    pub grids: Vec<GridSection>,
    /// A line on the points when they have no grids.
    pub points_line: Option<String>,
    /// Run statistics: `(name, value)` rows.
    pub run: Vec<(String, String)>,
    /// The run summary as printed.
    pub run_summary: String,
    /// Flag counts over all receivers: `(flag, count)`; empty when all pass.
    pub flags: Vec<(String, usize)>,
}

/// One luminaire of the scene.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Luminaire {
    /// Its name.
    pub name: String,
    /// Its type (`ies`, `ldt`, `point`, ...).
    pub kind: String,
    /// Its luminous flux \[lm\].
    pub flux: String,
    /// Its photometric file, if any.
    pub file: String,
    /// Its reference UGR, crosswise / endwise (CIE 117 tabular method,
    /// room 4H x 8H, reflectances 0.7 / 0.5 / 0.2, spacing 0.25 H, at its
    /// flux in the scene); `-` for a luminaire without type C photometry
    /// and a luminous area.
    pub ugr_ref: String,
}

/// One grid's section.
#[derive(Clone, Debug, Default, Serialize)]
pub struct GridSection {
    /// The grid's name.
    pub name: String,
    /// Facts: points, area, maintenance factor, batches.
    pub facts: Vec<(String, String)>,
    /// Warnings (flagged points, points left out, no scene grid).
    pub notes: Vec<String>,
    /// Figure rows.
    pub figures: Vec<FigureRow>,
    /// Requirement verdicts.
    pub verdicts: Vec<VerdictRow>,
    /// The isolux plot as SVG text, if one could be drawn.
    pub svg: Option<String>,
    /// Why there is no plot, or where its files were written.
    pub plot_note: Option<String>,
}

/// One figure of a grid, as in the `--figures-out` CSV.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FigureRow {
    /// `E_avg`, `E_min`, `E_max`, `U0`, `Ud`.
    pub figure: String,
    /// `lx` or `1`.
    pub unit: String,
    /// Shown value and full value.
    pub value: (String, String),
    /// Standard error, shown and full.
    pub std_error: (String, String),
    /// 95 % interval low end, shown and full.
    pub ci95_low: (String, String),
    /// 95 % interval high end, shown and full.
    pub ci95_high: (String, String),
    /// How the error was found.
    pub method: String,
    /// The requirement, if any (`>= 500`).
    pub required: String,
    /// Its verdict (`met`, `not met`, `undecided`), if any.
    pub verdict: String,
}

/// A requirement and its verdict.
#[derive(Clone, Debug, Default, Serialize)]
pub struct VerdictRow {
    /// What is required (`Em >= 500 lx`).
    pub requirement: String,
    /// `met`, `not met` or `undecided`.
    pub verdict: String,
    /// CSS class of the verdict.
    pub class: String,
}

/// The report as one HTML page.
pub fn render_html(r: &Report) -> Result<String, minijinja::Error> {
    let mut env = minijinja::Environment::new();
    env.set_auto_escape_callback(|_| minijinja::AutoEscape::Html);
    env.add_template("report.html", TEMPLATE)?;
    env.get_template("report.html")?
        .render(minijinja::context!(r => minijinja::value::Serde(r)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text is escaped; the SVG is inserted as is.
    #[test]
    fn escapes_text_and_keeps_svg() {
        let r = Report {
            title: "a <script>alert(1)</script> & b".into(),
            grids: vec![GridSection {
                name: "<desk>".into(),
                svg: Some("<svg id=\"p\"><text>1 &amp; 2</text></svg>".into()),
                verdicts: vec![VerdictRow {
                    requirement: "Em >= 500 lx".into(),
                    verdict: "not met".into(),
                    class: "not-met".into(),
                }],
                ..Default::default()
            }],
            ..Default::default()
        };
        let html = render_html(&r).unwrap();
        assert!(!html.contains("<script>alert"));
        assert!(html.contains("a &lt;script&gt;alert(1)&lt;&#x2f;script&gt; &amp; b"));
        assert!(html.contains("&lt;desk&gt;"));
        assert!(html.contains("<svg id=\"p\"><text>1 &amp; 2</text></svg>"));
        assert!(html.contains("Em &gt;= 500 lx"));
    }
}
