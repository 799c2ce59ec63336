//! The machinery of `tests/bad_inputs.rs`: a case's files, its command,
//! the run, the checks every case must pass and the markdown row.

use std::path::Path;
use std::process::Command;

/// The input channel a case exercises; each has its own file and command.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Debug)]
pub enum Ch {
    /// `s.toml`, run by `illuminance` on the plain points.
    Scene,
    /// `p.csv`, run by `illuminance` on the plain scene.
    Points,
    /// `v.csv`, run by `luminance` on the plain scene.
    Views,
    /// `m.obj`, a mesh in the plain scene (`illuminance`).
    Obj,
    /// `c.csv`, the coefficient file of an SH object in the plain scene.
    Sh,
    /// `f.ies`, read by `lumest photometry`.
    Ies,
    /// `f.ldt`, read by `lumest photometry`.
    Ldt,
    /// Command-line options (the plain files are there to name).
    Cli,
}

impl Ch {
    pub fn name(self) -> &'static str {
        match self {
            Ch::Scene => "scene TOML",
            Ch::Points => "points CSV",
            Ch::Views => "views CSV",
            Ch::Obj => "OBJ mesh",
            Ch::Sh => "SH coefficients",
            Ch::Ies => "IES file",
            Ch::Ldt => "EULUMDAT file",
            Ch::Cli => "command line",
        }
    }

    /// The file the channel's input is written to.
    pub fn file(self) -> Option<&'static str> {
        match self {
            Ch::Scene => Some("s.toml"),
            Ch::Points => Some("p.csv"),
            Ch::Views => Some("v.csv"),
            Ch::Obj => Some("m.obj"),
            Ch::Sh => Some("c.csv"),
            Ch::Ies => Some("f.ies"),
            Ch::Ldt => Some("f.ldt"),
            Ch::Cli => None,
        }
    }
}

/// What a case's input file holds.
pub enum Body {
    Text(String),
    Bytes(Vec<u8>),
    /// The file is absent.
    Missing,
    /// A folder stands where the file should be.
    Folder,
}

/// The outcome a case must have.
#[derive(Clone, Copy)]
pub enum Expect {
    /// Refused: a non-zero exit and an error containing this text (for a
    /// file channel the message must also name the file).
    Error(&'static str),
    /// Run, with this text in a line of the summary (a `WARNING`, a note).
    Warn(&'static str),
    /// Run, with this flag on some output row.
    Flag(&'static str),
    /// Run, with exactly the results of the plain input.
    Same,
    /// Run, with this text in its standard output, summary or output file.
    Accept(&'static str),
}

pub struct Case {
    pub ch: Ch,
    pub what: String,
    pub body: Body,
    /// Command line for `Ch::Cli` (`{s}`, `{p}`, `{v}`, `{m}`, `{c}`,
    /// `{ies}`, `{ldt}`, `{d}`: the plain files and the case's folder);
    /// extra options otherwise.
    pub args: Vec<String>,
    pub expect: Expect,
    /// Standard input for the command.
    pub stdin: Option<String>,
}

pub const SCENE: &str = r#"[[surface]]
name = "room"
type = "box"
min = [-2, -2, 0]
max = [2, 2, 3]
material = { type = "lambertian", reflectance = 0.5 }

[[light]]
name = "lamp"
type = "point"
position = [0, 0, 2.5]
intensity = 100.0
"#;

pub const POINTS: &str =
    "id,x,y,z,nx,ny,nz\na,0,0,0.75,0,0,1\nb,1,1,0.75,0,0,1\nc,-1,0.5,0.75,0,0,1\n";

pub const VIEWS: &str = "id,x,y,z,dx,dy,dz\na,0,0,1.5,0,0,-1\nb,1,1,1.5,1,0,0\n";

pub const OBJ: &str = "# a tetrahedron\nv 1 1 0.1\nv 1.3 1 0.1\nv 1 1.3 0.1\nv 1 1 0.4\n\
                       f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";

pub const MESH_SURFACE: &str = "\n[[surface]]\ntype = \"mesh\"\nfile = \"m.obj\"\n\
                                material = { type = \"lambertian\", reflectance = 0.5 }\n";

pub const COEFFS: &str = "k,m,a,b\n0,0,0.3,0\n1,0,0.05,0\n";

pub const SH_SURFACE: &str = "\n[[surface]]\ntype = \"sh\"\nfile = \"c.csv\"\ncenter = [-1, -1, 0.5]\n\
                              material = { type = \"lambertian\", reflectance = 0.5 }\n";

pub const IES: &str = "IESNA:LM-63-2002\n[TEST] bad input\nTILT=NONE\n\
                       1 1000 1 3 1 1 2 0 0 0\n1.0 1.0 20\n0 45 90\n0\n100 80 50\n";

/// The run options every Monte Carlo case uses: 32 batches of 32 chains.
pub const RUN: [&str; 7] = [
    "--chains",
    "1024",
    "--batch-size",
    "32",
    "--threads",
    "1",
    "--quiet",
];

/// The plain EULUMDAT file: `data/photometry/isym1.ldt`.
pub fn ldt() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/photometry/isym1.ldt"
    ))
    .unwrap()
}

/// What a run left: exit code, standard output and error, the output file.
pub struct Ran {
    pub code: Option<i32>,
    pub stdout: String,
    pub stderr: String,
    pub out: Option<String>,
}

fn put(dir: &Path, name: &str, body: &Body) {
    let p = dir.join(name);
    match body {
        Body::Text(t) => std::fs::write(p, t).unwrap(),
        Body::Bytes(b) => std::fs::write(p, b).unwrap(),
        Body::Missing => {}
        Body::Folder => std::fs::create_dir(p).unwrap(),
    }
}

/// Write the plain files of every channel, then the case's own.
pub fn prepare(dir: &Path, case: &Case) {
    let scene = match case.ch {
        Ch::Obj => format!("{SCENE}{MESH_SURFACE}"),
        Ch::Sh => format!("{SCENE}{SH_SURFACE}"),
        _ => SCENE.to_string(),
    };
    let plain: [(&str, Body); 7] = [
        ("s.toml", Body::Text(scene)),
        ("p.csv", Body::Text(POINTS.into())),
        ("v.csv", Body::Text(VIEWS.into())),
        ("m.obj", Body::Text(OBJ.into())),
        ("c.csv", Body::Text(COEFFS.into())),
        ("f.ies", Body::Text(IES.into())),
        ("f.ldt", Body::Text(ldt())),
    ];
    for (name, body) in &plain {
        if Some(*name) != case.ch.file() {
            put(dir, name, body);
        }
    }
    if let Some(f) = case.ch.file() {
        put(dir, f, &case.body);
    }
}

/// The command line of a case, and the output file it writes (if any).
pub fn command_line(dir: &Path, case: &Case) -> (Vec<String>, Option<String>) {
    let d = dir.to_string_lossy().into_owned();
    let f = |n: &str| format!("{d}/{n}");
    let run: Vec<String> = RUN.iter().map(|s| s.to_string()).collect();
    let mut args: Vec<String> = match case.ch {
        Ch::Scene | Ch::Points | Ch::Obj | Ch::Sh => {
            let mut a = vec![
                "illuminance".into(),
                "--scene".into(),
                f("s.toml"),
                "--points".into(),
                f("p.csv"),
                "--out".into(),
                f("out.csv"),
            ];
            a.extend(run);
            a
        }
        Ch::Views => {
            let mut a = vec![
                "luminance".into(),
                "--scene".into(),
                f("s.toml"),
                "--views".into(),
                f("v.csv"),
                "--out".into(),
                f("out.csv"),
            ];
            a.extend(run);
            a
        }
        Ch::Ies => vec!["photometry".into(), f("f.ies")],
        Ch::Ldt => vec!["photometry".into(), f("f.ldt")],
        Ch::Cli => Vec::new(),
    };
    let subst = |a: &str| {
        a.replace("{s}", &f("s.toml"))
            .replace("{p}", &f("p.csv"))
            .replace("{v}", &f("v.csv"))
            .replace("{m}", &f("m.obj"))
            .replace("{c}", &f("c.csv"))
            .replace("{ies}", &f("f.ies"))
            .replace("{ldt}", &f("f.ldt"))
            .replace("{d}", &d)
    };
    args.extend(case.args.iter().map(|a| subst(a)));
    let out = match case.ch {
        Ch::Ies | Ch::Ldt => None,
        Ch::Cli => args
            .iter()
            .position(|a| a == "--out")
            .and_then(|k| args.get(k + 1))
            .filter(|o| o.ends_with(".csv"))
            .cloned(),
        _ => Some(f("out.csv")),
    };
    (args, out)
}

/// Run a case in `dir`.
pub fn run(dir: &Path, case: &Case) -> Ran {
    prepare(dir, case);
    let (args, out) = command_line(dir, case);
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lumest"));
    cmd.args(&args).current_dir(dir);
    let o = if let Some(input) = &case.stdin {
        use std::io::Write;
        cmd.stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        let mut child = cmd.spawn().unwrap();
        child
            .stdin
            .take()
            .unwrap()
            .write_all(input.as_bytes())
            .unwrap();
        child.wait_with_output().unwrap()
    } else {
        cmd.output().unwrap()
    };
    let out_text = out.and_then(|o| std::fs::read_to_string(o).ok());
    Ran {
        code: o.status.code(),
        stdout: String::from_utf8_lossy(&o.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&o.stderr).into_owned(),
        out: out_text,
    }
}

/// The named column of a CSV text, as strings.
pub fn column(csv: &str, name: &str) -> Vec<String> {
    let mut lines = csv.lines();
    let Some(head) = lines.next() else {
        return Vec::new();
    };
    let Some(k) = head.split(',').position(|h| h == name) else {
        return Vec::new();
    };
    lines
        .map(|l| l.split(',').nth(k).unwrap_or("").to_string())
        .collect()
}

/// A word of `text` that reads as a non-finite number.
pub fn non_finite(text: &str) -> Option<String> {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+'))
        .find(|w| {
            let w = w.trim_start_matches(['-', '+']).to_ascii_lowercase();
            w == "nan" || w == "inf" || w == "infinity"
        })
        .map(str::to_string)
}

/// The line of `text` containing `want`, or the first line.
pub fn line_with<'a>(text: &'a str, want: &str) -> &'a str {
    text.lines()
        .find(|l| l.contains(want))
        .or_else(|| text.lines().find(|l| !l.trim().is_empty()))
        .unwrap_or("")
}

/// The error line of a failed run (lumest's own or the argument parser's).
pub fn error_line(stderr: &str) -> &str {
    stderr
        .lines()
        .find(|l| l.starts_with("lumest: error:") || l.starts_with("error:"))
        .or_else(|| stderr.lines().find(|l| !l.trim().is_empty()))
        .unwrap_or("")
}
