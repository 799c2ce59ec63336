//! `lumest validate daylight` (issue 13 items 8 and 9): the daylight
//! lights against references that share no code with lumest's light
//! models or estimators, error against run time for each.
//!
//! - **(a)** a uniform environment map (`L` = 1000 cd/m^2) over an open
//!   floor of reflectance 0.5: `E = pi L` facing up, `rho pi L` facing down
//!   (the infinite floor's luminance is `rho L` everywhere).
//! - **(b)** the traditional CIE overcast sky over a black floor:
//!   `E_h = 7 pi L_z / 9` facing up; facing the four horizontal directions,
//!   a midpoint rule over the hemisphere (checked itself against the closed
//!   form `E_v = L_z (3 pi + 8) / 18`).
//! - **(c)** a distant light over a black floor, a point and a 0.53 degree
//!   disc, at angles 0 to 120
//!   degrees to the receivers' normals: `E = E_n max(0, cos)`, exact; the
//!   rows check the exact part to rounding.
//! - **(d)** a 2 x 1.2 m window in a black 4 x 4 x 3 m room under the
//!   overcast sky, without and with a portal over the window: the sky
//!   component by 2-D Gauss-Legendre quadrature of `L cos cos / d^2` over
//!   the opening, split at the receiver's horizon (directions below it see
//!   the black ground).
//! - **(e)** the shipped probe `data/probes/sky_sun.hdr` (scale 100, no
//!   obstruction) at six normals: the importance-sampled map, and median cut
//!   with 16, 64 and 256 lights, against the exact pixel quadrature of the
//!   map (8 x 8 points equal in solid angle per pixel, written here). Median
//!   cut is an approximation: its rows report their bias and are not
//!   z-tested ([`Verdict::Biased`], [`BIASED_REASON`]).
//!
//! Every other row is z-tested against a Sidak bound over all z-tested
//! rows; a non-finite number is `FAIL`, and a row whose diagnostics raise a
//! flag is `flagged`, never `pass` (the checks hold their false-alarm rate
//! over the same rows, not per run: `Tallies::diagnostics_among`). The command fails unless every tested
//! row passes.

use super::case::CaseArgs;
use super::report::{Checkpoint, checkpoint, checkpoint_csv, loglog_slope, print_table};
use super::report::{write_report, z_against_exact};
use crate::estimator::local::run;
use crate::estimator::{Receiver, Receivers};
use crate::io::csvio::to_csv;
use crate::io::envmap::read_luminance_map;
use crate::io::image::{LuminanceImage, write_hdr};
use crate::io::plot::{Series, loglog_svg};
use crate::io::{format_number, write_atomic};
use crate::run::{RunConfig, Stop};
use crate::scene::{Scene, parse};
use crate::tally::{sidak_bound, zcheck};
use clap::Args;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::{Path, PathBuf};

/// Arguments of `lumest validate daylight`.
#[derive(Args, Clone, Debug)]
pub struct DaylightArgs {
    /// The references to run, by letter: a (uniform environment), b
    /// (overcast sky), c (distant light), d (window of a black room, with and
    /// without a portal), e (the probe: importance sampling against median
    /// cut with 16, 64 and 256 lights).
    #[arg(long, default_value = "abcde")]
    pub only: String,
    /// Double the chains up to this count instead of up to `--time`: the
    /// same runs on every machine.
    #[arg(long)]
    pub max_chains: Option<u64>,
    /// The probe of reference (e) (default: the shipped `data/probes/sky_sun.hdr`).
    #[arg(long)]
    pub probe: Option<PathBuf>,
    /// Run controls and report: the runs of each reference double their chains
    /// until one lasts `--time / 2` (s) or more (about `2 T` per reference).
    #[command(flatten)]
    pub case: CaseArgs,
}

/// Why median cut's rows are not z-tested against the exact value.
pub const BIASED_REASON: &str = "median cut replaces the map by N collimated lights of \
    equal energy: a deterministic approximation whose direct light is exact for those lights \
    (zero standard error), so its error is a bias that no run time reduces; the bias against \
    the exact pixel quadrature is reported, not z-tested";

/// Outcome of one row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Finite, no diagnostics flag, `|z|` within the Sidak bound.
    Pass,
    /// Finite and `|z|` within the bound, but a diagnostics flag: not a pass.
    Flagged,
    /// A non-finite number, or `|z|` beyond the bound (whatever the flags).
    Fail,
    /// An approximation (median cut): finite, bias reported, not z-tested
    /// ([`BIASED_REASON`]).
    Biased,
}

impl Verdict {
    /// `pass`, `flagged`, `FAIL` or `biased (approximation)`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Flagged => "flagged",
            Verdict::Fail => "FAIL",
            Verdict::Biased => "biased (approximation)",
        }
    }
}

/// One reference: a scene, its receivers and their exact values \[lx\].
struct Reference {
    /// File-name key, `daylight_<key>_*`.
    key: String,
    /// Heading.
    title: String,
    scene: Scene,
    /// Point labels (no spaces).
    labels: Vec<String>,
    receivers: Vec<Receiver>,
    /// Exact illuminance \[lx\]; the zeros come last.
    exact: Vec<f64>,
    /// Median cut: an approximation, not z-tested.
    approximation: bool,
}

/// A row of the verdict table: one point of one reference.
#[derive(Clone, Debug)]
pub struct Row {
    /// Reference key.
    pub reference: String,
    /// Point label.
    pub point: String,
    /// Receiver position \[m\] and normal.
    pub p: DVec3,
    /// Receiver normal.
    pub n: DVec3,
    /// Exact illuminance \[lx\].
    pub exact: f64,
    /// Estimate \[lx\].
    pub estimate: f64,
    /// Its standard error \[lx\].
    pub std_error: f64,
    /// Exact (unsampled) direct part of the estimate \[lx\].
    pub direct: f64,
    /// z against the exact value ([`z_against_exact`]).
    pub z: f64,
    /// Sidak bound on |z| (NaN for an approximation).
    pub bound: f64,
    /// Diagnostics flag (`ok` or the failed checks).
    pub flag: String,
    /// Batches, chains and wall time \[s\] of the run.
    pub batches: u64,
    /// Chains of the run.
    pub chains: u64,
    /// Wall time \[s\].
    pub time: f64,
    /// Verdict.
    pub verdict: Verdict,
}

impl Row {
    /// Relative error `estimate / exact - 1` (the bias of an approximation).
    pub fn rel_err(&self) -> f64 {
        if self.exact == 0.0 {
            self.estimate.abs()
        } else {
            self.estimate / self.exact - 1.0
        }
    }
}

/// Judge a row against the bound `bound` (module doc).
pub fn judge(r: &Row, approximation: bool) -> Verdict {
    let finite = [r.estimate, r.std_error, r.exact, r.direct]
        .into_iter()
        .all(f64::is_finite);
    if !finite {
        return Verdict::Fail;
    }
    // An approximation's rows carry the `approx` flag (the scene's lights
    // approximate it), and that flag alone.
    if approximation {
        return if r.flag == "approx" {
            Verdict::Biased
        } else {
            Verdict::Flagged
        };
    }
    if !zcheck::within(r.z, r.bound) || !r.z.is_finite() {
        return Verdict::Fail;
    }
    if r.flag != "ok" {
        return Verdict::Flagged;
    }
    Verdict::Pass
}

fn build(src: &str, dir: &Path) -> anyhow::Result<Scene> {
    parse(src, &dir.join("daylight.toml")).map_err(|e| anyhow::anyhow!("{e}"))
}

/// A black (or `rho`) infinite floor at z = 0.
fn floor(rho: f64) -> String {
    format!(
        "[[surface]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\nmaterial = {{ type = \"lambertian\", reflectance = {rho:?} }}\n\n"
    )
}

fn illum(pts: &[(DVec3, DVec3)]) -> Vec<Receiver> {
    pts.iter()
        .map(|&(p, n)| Receiver::illuminance(p, n))
        .collect()
}

/// (a) A uniform map of 1000 cd/m^2 over a floor of reflectance 0.5.
fn uniform_environment(dir: &Path) -> anyhow::Result<Reference> {
    let map = LuminanceImage::from_fn(16, 8, |_, _| 1.0)?;
    write_hdr(&map, &dir.join("uniform.hdr").to_string_lossy())?;
    let (l, rho) = (1000.0, 0.5);
    let scene = build(
        &format!(
            "{}[[light]]\ntype = \"environment\"\nfile = \"uniform.hdr\"\nscale = {l:?}\n",
            floor(rho)
        ),
        dir,
    )?;
    let pts = [
        ("up-on-floor", DVec3::new(0.0, 0.0, 0.0), DVec3::Z, PI * l),
        ("up-1.2m", DVec3::new(3.0, -2.0, 1.2), DVec3::Z, PI * l),
        (
            "down-1m",
            DVec3::new(0.0, 0.0, 1.0),
            -DVec3::Z,
            rho * PI * l,
        ),
        (
            "down-2m",
            DVec3::new(-1.5, 2.0, 2.0),
            -DVec3::Z,
            rho * PI * l,
        ),
    ];
    Ok(Reference {
        key: "a_uniform_environment".into(),
        title: "(a) uniform environment (1000 cd/m^2) over an open floor (rho 0.5): pi L up, rho pi L down".into(),
        scene,
        labels: pts.iter().map(|p| p.0.to_string()).collect(),
        receivers: illum(&pts.iter().map(|p| (p.1, p.2)).collect::<Vec<_>>()),
        exact: pts.iter().map(|p| p.3).collect(),
        approximation: false,
    })
}

/// `int L(w) max(0, n . w) dw` over the upper hemisphere by the midpoint
/// rule on a 600 x 2400 grid in (zenith angle, azimuth).
fn hemisphere_quadrature(l: &dyn Fn(DVec3) -> f64, n: DVec3) -> f64 {
    let (nz, na) = (600, 2400);
    let mut s = 0.0;
    for i in 0..nz {
        let z = FRAC_PI_2 * (i as f64 + 0.5) / nz as f64;
        for j in 0..na {
            let a = 2.0 * PI * (j as f64 + 0.5) / na as f64;
            let w = DVec3::new(z.sin() * a.cos(), z.sin() * a.sin(), z.cos());
            let c = n.dot(w);
            if c > 0.0 {
                s += l(w) * c * z.sin();
            }
        }
    }
    s * (FRAC_PI_2 / nz as f64) * (2.0 * PI / na as f64)
}

/// The traditional CIE overcast sky, written here: `L_z (1 + 2 cos Z) / 3`
/// above the horizon, 0 below.
fn overcast(lz: f64, w: DVec3) -> f64 {
    if w.z >= 0.0 {
        lz * (1.0 + 2.0 * w.z) / 3.0
    } else {
        0.0
    }
}

/// (b) The overcast sky (L_z = 9000 cd/m^2) over a black floor.
fn overcast_sky(dir: &Path) -> anyhow::Result<Reference> {
    let lz = 9000.0;
    let scene = build(
        &format!(
            "{}[[light]]\ntype = \"sky\"\nsky = \"overcast\"\nzenith_luminance = {lz:?}\n",
            floor(0.0)
        ),
        dir,
    )?;
    let l = |w: DVec3| overcast(lz, w);
    let mut pts = vec![("up", DVec3::Z, 7.0 * PI * lz / 9.0)];
    for (name, n) in [
        ("east", DVec3::X),
        ("north", DVec3::Y),
        ("west", -DVec3::X),
        ("south", -DVec3::Y),
    ] {
        let q = hemisphere_quadrature(&l, n);
        // The quadrature against the vertical closed form (no ground light).
        let closed = lz * (3.0 * PI + 8.0) / 18.0;
        anyhow::ensure!(
            (q / closed - 1.0).abs() < 1e-6,
            "internal: vertical quadrature {q} against the closed form {closed}"
        );
        pts.push((name, n, q));
    }
    Ok(Reference {
        key: "b_overcast_sky".into(),
        title: "(b) CIE overcast sky (L_z 9000 cd/m^2) over a black floor: 7 pi L_z / 9 up, quadrature vertical".into(),
        scene,
        labels: pts.iter().map(|p| format!("{}-0.5m", p.0)).collect(),
        receivers: illum(
            &pts.iter()
                .map(|p| (DVec3::new(0.0, 0.0, 0.5), p.1))
                .collect::<Vec<_>>(),
        ),
        exact: pts.iter().map(|p| p.2).collect(),
        approximation: false,
    })
}

/// (c) A distant light (E_n = 80,000 lx, 35 degrees up) over a black floor,
/// a point (`diameter` 0) or a disc of `diameter` \[deg\]; receivers at
/// angles 0-120 degrees to the beam. A uniform disc wholly above the
/// receiver's horizon gives exactly `E_n cos` too (`L n . int_cap w dw`
/// with `int_cap w dw = pi sin^2(d/2)` times the axis); none of the angles
/// is within the disc's radius of 90 degrees.
fn distant_light(dir: &Path, diameter: f64) -> anyhow::Result<Reference> {
    let e_n = 80000.0;
    let (h, a) = (35f64.to_radians(), 140f64.to_radians());
    let to_sun = DVec3::new(h.cos() * a.cos(), h.cos() * a.sin(), h.sin());
    let d = -to_sun;
    let scene = build(
        &format!(
            "{}[[light]]\ntype = \"distant\"\ndirection = [{:?}, {:?}, {:?}]\nilluminance = {e_n:?}\nangular_diameter = {diameter:?}\n",
            floor(0.0),
            d.x,
            d.y,
            d.z
        ),
        dir,
    )?;
    // Normals at angle t from the sun, rotated about the horizontal axis
    // across the sun's direction (so the 0-80 degree ones stay above the floor).
    let side = to_sun.cross(DVec3::Z).normalize();
    let up = side.cross(to_sun).normalize(); // towards the zenith
    let mut pts = Vec::new();
    for deg in [0.0f64, 30.0, 55.0, 80.0, 100.0, 120.0] {
        let t = deg.to_radians();
        let n = (to_sun * t.cos() + up * t.sin()).normalize();
        let exact = e_n * n.dot(to_sun).max(0.0);
        pts.push((
            format!("angle-{deg:.0}"),
            DVec3::new(0.3, -0.2, 0.5),
            n,
            exact,
        ));
    }
    pts.push((
        "floor-up".into(),
        DVec3::new(2.0, 1.0, 0.0),
        DVec3::Z,
        e_n * h.sin(),
    ));
    // Zeros last.
    pts.sort_by_key(|p| p.3 == 0.0);
    let (key, title) = if diameter == 0.0 {
        ("c_distant_light".to_string(), "point".to_string())
    } else {
        (
            "c_distant_disc".to_string(),
            format!("disc of {diameter} deg"),
        )
    };
    Ok(Reference {
        key,
        title: format!(
            "(c) distant light ({title}, 80 klx, 35 deg up) over a black floor: E_n cos at 0-120 deg (exact)"
        ),
        scene,
        labels: pts.iter().map(|p| p.0.clone()).collect(),
        receivers: illum(&pts.iter().map(|p| (p.1, p.2)).collect::<Vec<_>>()),
        exact: pts.iter().map(|p| p.3).collect(),
        approximation: false,
    })
}

/// The window of (d): x = 0, y in [1, 3], z in [0.9, 2.1].
const WINDOW: (f64, f64, f64, f64) = (1.0, 3.0, 0.9, 2.1);

/// (d) The black room with its window under the overcast sky (L_z = 10,000
/// cd/m^2), with or without a portal over the window.
fn window_room(dir: &Path, portal: bool) -> anyhow::Result<Reference> {
    let lz = 10000.0;
    let rect = |c: [f64; 3], e1: [f64; 3], e2: [f64; 3]| {
        format!(
            "[[surface]]\ntype = \"rectangle\"\ncorner = {c:?}\nedge1 = {e1:?}\nedge2 = {e2:?}\nsides = \"both\"\nmaterial = {{ type = \"lambertian\", reflectance = 0.0 }}\n\n"
        )
    };
    let (y0, y1, z0, z1) = WINDOW;
    let mut s = String::new();
    s += &rect([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]); // floor
    s += &rect([0.0, 0.0, 3.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0]); // ceiling
    s += &rect([4.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 3.0]); // x = 4
    s += &rect([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 0.0, 3.0]); // y = 0
    s += &rect([0.0, 4.0, 0.0], [4.0, 0.0, 0.0], [0.0, 0.0, 3.0]); // y = 4
    // The wall x = 0 around the window.
    s += &rect([0.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, z0]);
    s += &rect([0.0, 0.0, z1], [0.0, 4.0, 0.0], [0.0, 0.0, 3.0 - z1]);
    s += &rect([0.0, 0.0, z0], [0.0, y0, 0.0], [0.0, 0.0, z1 - z0]);
    s += &rect([0.0, y1, z0], [0.0, 4.0 - y1, 0.0], [0.0, 0.0, z1 - z0]);
    s += &format!("[[light]]\ntype = \"sky\"\nsky = \"overcast\"\nzenith_luminance = {lz:?}\n\n");
    if portal {
        s += &format!(
            "[[portal]]\ncorner = [0.0, {y0:?}, {z0:?}]\nedge1 = [0.0, {:?}, 0.0]\nedge2 = [0.0, 0.0, {:?}]\n",
            y1 - y0,
            z1 - z0
        );
    }
    let scene = build(&s, dir)?;
    let pts = [
        ("near-window-up", DVec3::new(1.0, 2.0, 0.8), DVec3::Z),
        ("mid-up", DVec3::new(2.0, 1.5, 0.8), DVec3::Z),
        ("back-corner-up", DVec3::new(3.0, 3.0, 0.8), DVec3::Z),
        ("facing-window", DVec3::new(2.0, 2.0, 1.5), -DVec3::X),
        (
            "tilted",
            DVec3::new(1.5, 1.0, 1.0),
            DVec3::new(-1.0, 0.5, 1.0).normalize(),
        ),
    ];
    let exact = pts
        .iter()
        .map(|&(_, p, n)| window_sky_component(lz, p, n.normalize()))
        .collect();
    let (key, title) = if portal {
        ("d_window_portal", "with a portal")
    } else {
        ("d_window", "no portal")
    };
    Ok(Reference {
        key: key.into(),
        title: format!(
            "(d) 2 x 1.2 m window of a black room under the overcast sky ({title}): sky component by 2-D Gauss-Legendre"
        ),
        scene,
        labels: pts.iter().map(|p| p.0.to_string()).collect(),
        receivers: illum(&pts.iter().map(|p| (p.1, p.2)).collect::<Vec<_>>()),
        exact,
        approximation: false,
    })
}

/// The sky component at `p` (normal `n`) through [`WINDOW`]:
/// `int L(w) max(0, n . w) cos_w / d^2 dA` over the opening, by 2-D
/// Gauss-Legendre (4 panels of 16 nodes each way), the heights split at the
/// receiver's horizon `z = p.z` (below it the black ground: no light).
fn window_sky_component(lz: f64, p: DVec3, n: DVec3) -> f64 {
    let (y0, y1, z0, z1) = WINDOW;
    let z_lo = z0.max(p.z);
    if z_lo >= z1 {
        return 0.0;
    }
    let gl = gauss_quad::legendre::GaussLegendre::new(
        std::num::NonZeroUsize::new(16).expect("16 nodes"),
    );
    let nodes = gl.as_node_weight_pairs();
    let panels = 4;
    let integral = |a: f64, b: f64, f: &dyn Fn(f64) -> f64| {
        let h = (b - a) / panels as f64;
        let mut s = 0.0;
        for k in 0..panels {
            let (c, r) = (a + h * (k as f64 + 0.5), 0.5 * h);
            for &(x, w) in nodes {
                s += w * r * f(c + r * x);
            }
        }
        s
    };
    integral(y0, y1, &|y| {
        integral(z_lo, z1, &|z| {
            let d = DVec3::new(0.0, y, z) - p;
            let d2 = d.length_squared();
            let w = d / d2.sqrt();
            let cos_p = n.dot(w).max(0.0);
            let cos_w = -w.x; // the window's normal is +x, into the room
            overcast(lz, w) * cos_p * cos_w / d2
        })
    })
}

/// The methods of (e): importance sampling, then median cut with N lights.
const PROBE_METHODS: [(&str, Option<usize>); 4] = [
    ("importance", None),
    ("median-cut-16", Some(16)),
    ("median-cut-64", Some(64)),
    ("median-cut-256", Some(256)),
];

/// (e) The probe (scale 100, nothing in the scene) at six normals, by each
/// of [`PROBE_METHODS`].
fn probe(dir: &Path, probe: &Path) -> anyhow::Result<Vec<Reference>> {
    let scale = 100.0;
    let map = read_luminance_map(probe).map_err(|e| anyhow::anyhow!("{e}"))?;
    let az = 45f64.to_radians(); // the probe's sun azimuth
    let hz = DVec3::new(az.cos(), az.sin(), 0.0);
    let s = 0.5f64.sqrt();
    let normals = [
        ("up", DVec3::Z),
        ("tilt-to-sun", (hz * s + DVec3::Z * s).normalize()),
        ("tilt-away", (-hz * s + DVec3::Z * s).normalize()),
        ("vertical-to-sun", hz),
        ("vertical-away", -hz),
        ("vertical-side", DVec3::new(-az.sin(), az.cos(), 0.0)),
    ];
    let exact: Vec<f64> = normals
        .iter()
        .map(|&(_, n)| {
            crate::reference::envmap::pixel_quadrature(&map.y, map.width, map.height, scale, n)
        })
        .collect();
    let file = probe
        .canonicalize()
        .map_err(|e| anyhow::anyhow!("--probe {}: {e}", probe.display()))?;
    let mut refs = Vec::new();
    for (name, lights) in PROBE_METHODS {
        let sampling = lights.map_or(String::new(), |n| {
            format!("sampling = \"median-cut\"\nlights = {n}\n")
        });
        let scene = build(
            &format!(
                "[[light]]\ntype = \"environment\"\nfile = {:?}\nscale = {scale:?}\n{sampling}",
                file.to_string_lossy()
            ),
            dir,
        )?;
        refs.push(Reference {
            key: format!("e_probe_{}", name.replace('-', "_")),
            title: format!(
                "(e) probe {} (scale 100), {name}: against pixel quadrature{}",
                probe.display(),
                if lights.is_some() {
                    " (an approximation: bias, not z-tested)"
                } else {
                    ""
                }
            ),
            scene,
            labels: normals.iter().map(|n| n.0.to_string()).collect(),
            receivers: illum(
                &normals
                    .iter()
                    .map(|&(_, n)| (DVec3::ZERO, n))
                    .collect::<Vec<_>>(),
            ),
            exact: exact.clone(),
            approximation: lights.is_some(),
        });
    }
    Ok(refs)
}

/// Chains of the first run of a reference: 32 batches of 256.
const FIRST_CHAINS: u64 = 8192;

/// Run one reference at a doubling sequence of chain counts (independent
/// runs of the same seed, each stopped by its chain count, so each is
/// reproducible), from [`FIRST_CHAINS`] until a run lasts at least half of
/// `--time` (so the last lasts about `T/2` to `T`, all of them about `2T`),
/// or up to `max_chains`;
/// each run's error against the exact values is a row of the table, and
/// the last run's points are the rows of the verdict table, z-tested
/// against the Sidak bound over `alpha_m` rows, over which their
/// statistical checks also hold their false-alarm rate.
fn run_reference(
    r: &Reference,
    a: &CaseArgs,
    max_chains: Option<u64>,
    alpha_m: usize,
) -> anyhow::Result<(Vec<Checkpoint>, Vec<Row>)> {
    let receivers =
        Receivers::from_receivers(&r.scene, &r.receivers).map_err(|e| anyhow::anyhow!("{e}"))?;
    let nz = r.exact.iter().take_while(|&&e| e != 0.0).count();
    anyhow::ensure!(
        nz > 0 && r.exact[nz..].iter().all(|&e| e == 0.0),
        "internal: receivers with exact value 0 must come last"
    );
    let mut table = Vec::new();
    let mut chains = FIRST_CHAINS;
    let result = loop {
        let cfg = RunConfig {
            seed: a.seed,
            threads: a.threads,
            stop: Stop {
                chains: Some(chains),
                ..Stop::default()
            },
            // At least 32 batches of at least 256 chains, 256 batches from
            // 65,536 chains on: with 64 the diagnostics' FOM check (R^2 B at
            // half the batches against the end) flagged a correct row of the
            // portal-less window at 8.4e6 chains (z -1.4), its R^2 estimated
            // from too few batch means.
            batch_size: Some((chains / 256).max(256)),
            ..RunConfig::default()
        };
        let result = run(&r.scene, &receivers, &cfg, &mut |_| true);
        let c = checkpoint(&result.progress(), &r.exact, 0..nz);
        if !a.quiet {
            eprintln!("lumest: {}: {} chains in {:.3} s", r.key, c.chains, c.time);
        }
        // An approximation's table carries no z either.
        table.push(if r.approximation {
            Checkpoint {
                max_z: f64::NAN,
                ..c
            }
        } else {
            c
        });
        let done = match max_chains {
            Some(n) => 2 * chains > n,
            None => c.time >= 0.5 * a.time,
        };
        if done || chains >= 1 << 40 {
            break result;
        }
        chains *= 2;
    };
    let p = result.progress();
    let batches = result.tallies.batches();
    let bound = if r.approximation {
        f64::NAN
    } else {
        sidak_bound(a.alpha, alpha_m, Some(batches.max(2)))
    };
    let rows = (0..r.exact.len())
        .map(|j| {
            let w = &result.tallies.estimated[j];
            let e = result.direct[j] + w.mean();
            let mut row = Row {
                reference: r.key.clone(),
                point: r.labels[j].clone(),
                p: r.receivers[j].p,
                n: r.receivers[j].n,
                exact: r.exact[j],
                estimate: e,
                std_error: w.std_error(),
                direct: result.direct[j],
                // An approximation is not z-tested: no z.
                z: if r.approximation {
                    f64::NAN
                } else {
                    z_against_exact(e, w.std_error(), result.direct[j], r.exact[j])
                },
                bound,
                // The checks' false alarms held over every gated row of the
                // command (the Sidak family), as the gate fails on any
                // flagged row: held per run they would fail a sound command
                // in about 0.1 % times its runs, per check.
                flag: result
                    .tallies
                    .diagnostics_among(j, result.direct[j], alpha_m)
                    .flag(),
                batches,
                chains: p.chains,
                time: p.elapsed,
                verdict: Verdict::Fail,
            };
            row.verdict = judge(&row, r.approximation);
            row
        })
        .collect();
    Ok((table, rows))
}

/// Print and write a reference's table of error against time: the plot
/// only where there is an error to plot (an exact reference's errors are 0).
fn report_table(dir: &Path, r: &Reference, rows: &[Checkpoint]) -> anyhow::Result<()> {
    println!("\n## {}", r.title);
    print_table(rows);
    let name = format!("daylight_{}", r.key);
    if rows.iter().any(|c| c.rms_err > 0.0 || c.rms_r > 0.0) {
        if !r.approximation && rows.len() > 1 && rows.iter().all(|c| c.rms_r > 0.0) {
            let slope = loglog_slope(&rows.iter().map(|c| (c.time, c.rms_r)).collect::<Vec<_>>());
            println!("log-log slope of the estimated R against time: {slope:.3} (ideal -0.5)");
        }
        write_report(dir, &name, rows, &r.title)
    } else {
        std::fs::create_dir_all(dir)?;
        let path = dir.join(format!("{name}_convergence.csv"));
        write_atomic(&path.to_string_lossy(), &checkpoint_csv(rows))?;
        eprintln!(
            "lumest: wrote {} (every error is 0: no plot)",
            path.display()
        );
        Ok(())
    }
}

fn print_rows(rows: &[Row]) {
    println!(
        "{:<16} {:>14} {:>14} {:>10} {:>11} {:>9} {:>6} {:<8} verdict",
        "point", "exact [lx]", "estimate", "stderr", "rel_err", "z", "bound", "flag"
    );
    for r in rows {
        let (z, bound) = if r.verdict == Verdict::Biased {
            ("-".to_string(), "-".to_string())
        } else {
            (format!("{:.3}", r.z), format!("{:.2}", r.bound))
        };
        println!(
            "{:<16} {:>14.6e} {:>14.6e} {:>10.3e} {:>+11.3e} {:>9} {:>6} {:<8} {}",
            r.point,
            r.exact,
            r.estimate,
            r.std_error,
            r.rel_err(),
            z,
            bound,
            r.flag,
            r.verdict.as_str()
        );
    }
}

fn points_csv(rows: &[Row]) -> Vec<u8> {
    let headers: Vec<String> = [
        "reference",
        "point",
        "x",
        "y",
        "z",
        "nx",
        "ny",
        "nz",
        "exact",
        "estimate",
        "stderr",
        "direct",
        "rel_err",
        "z_score",
        "bound",
        "flag",
        "batches",
        "chains",
        "time_s",
        "verdict",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let cells: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let mut c = vec![r.reference.clone(), r.point.clone()];
            c.extend(
                [r.p.x, r.p.y, r.p.z, r.n.x, r.n.y, r.n.z]
                    .iter()
                    .chain(&[
                        r.exact,
                        r.estimate,
                        r.std_error,
                        r.direct,
                        r.rel_err(),
                        r.z,
                        r.bound,
                    ])
                    .map(|&v| format_number(v)),
            );
            c.push(r.flag.clone());
            c.push(r.batches.to_string());
            c.push(r.chains.to_string());
            c.push(format_number(r.time));
            c.push(r.verdict.as_str().to_string());
            c
        })
        .collect();
    to_csv(&headers, &cells)
}

/// The side-by-side comparison of (e): RMS relative error against time of
/// each method, and importance sampling's estimated error, in one table
/// and one plot.
fn probe_comparison(dir: &Path, tables: &[(String, Vec<Checkpoint>)]) -> anyhow::Result<()> {
    let headers: Vec<String> = [
        "method",
        "time_s",
        "chains",
        "rms_rel_err",
        "max_rel_err",
        "rms_rel_stderr",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut cells = Vec::new();
    let mut series = Vec::new();
    for (name, rows) in tables {
        for c in rows {
            cells.push(vec![
                name.clone(),
                format_number(c.time),
                c.chains.to_string(),
                format_number(c.rms_err),
                format_number(c.max_err),
                format_number(c.rms_r),
            ]);
        }
        series.push(Series {
            name: format!("{name}: RMS |E - E_exact| / E_exact"),
            points: rows.iter().map(|c| (c.time, c.rms_err)).collect(),
            dashed: false,
        });
        if name == "importance" {
            series.push(Series {
                name: "importance: RMS estimated std error R".into(),
                points: rows.iter().map(|c| (c.time, c.rms_r)).collect(),
                dashed: true,
            });
        }
    }
    std::fs::create_dir_all(dir)?;
    let csv = dir.join("daylight_e_comparison.csv");
    write_atomic(&csv.to_string_lossy(), &to_csv(&headers, &cells))?;
    let svg = loglog_svg(
        "sky_sun.hdr: importance sampling against median cut (exact: pixel quadrature)",
        "wall time T [s]",
        "relative error against the exact value",
        &series,
    )
    .map_err(|e| anyhow::anyhow!("plot: {e}"))?;
    let svg_path = dir.join("daylight_e_comparison.svg");
    write_atomic(&svg_path.to_string_lossy(), svg.as_bytes())?;
    eprintln!("lumest: wrote {} and {}", csv.display(), svg_path.display());
    println!("\n## (e) side by side: RMS relative error over the six normals against run time");
    println!(
        "{:<16} {:>9} {:>12} {:>12} {:>12}",
        "method", "time_s", "chains", "rms_rel_err", "rms_R"
    );
    for (name, rows) in tables {
        for c in rows {
            println!(
                "{:<16} {:>9.3} {:>12} {:>12.3e} {:>12.3e}",
                name, c.time, c.chains, c.rms_err, c.rms_r
            );
        }
    }
    Ok(())
}

/// Run `lumest validate daylight`.
pub fn validate_daylight(a: &DaylightArgs) -> anyhow::Result<()> {
    let c = &a.case;
    anyhow::ensure!(
        c.time > 0.0 && c.time.is_finite(),
        "--time must be positive"
    );
    anyhow::ensure!(
        !a.only.is_empty() && a.only.chars().all(|ch| "abcde".contains(ch)),
        "--only {}: give letters among a, b, c, d, e (e.g. `abcd`)",
        a.only
    );
    anyhow::ensure!(
        a.max_chains.is_none_or(|n| n >= FIRST_CHAINS),
        "--max-chains must be at least {FIRST_CHAINS}"
    );
    let dir = c.report.join("daylight_scenes");
    std::fs::create_dir_all(&dir)?;
    let want = |ch: char| a.only.contains(ch);
    let mut refs = Vec::new();
    if want('a') {
        refs.push(uniform_environment(&dir)?);
    }
    if want('b') {
        refs.push(overcast_sky(&dir)?);
    }
    if want('c') {
        refs.push(distant_light(&dir, 0.0)?);
        refs.push(distant_light(&dir, 0.53)?);
    }
    if want('d') {
        refs.push(window_room(&dir, false)?);
        refs.push(window_room(&dir, true)?);
    }
    if want('e') {
        let default = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/probes/sky_sun.hdr");
        refs.extend(probe(&dir, a.probe.as_deref().unwrap_or(&default))?);
    }
    // The Sidak family: every row of an exact reference.
    let m: usize = refs
        .iter()
        .filter(|r| !r.approximation)
        .map(|r| r.exact.len())
        .sum();
    let mut all = Vec::new();
    let mut probe_tables = Vec::new();
    for r in &refs {
        let (table, rows) = run_reference(r, c, a.max_chains, m)?;
        report_table(&c.report, r, &table)?;
        print_rows(&rows);
        if r.key.starts_with("e_probe_") {
            probe_tables.push((r.key["e_probe_".len()..].replace('_', "-"), table));
        }
        all.extend(rows);
    }
    if !probe_tables.is_empty() {
        probe_comparison(&c.report, &probe_tables)?;
        println!("\nmedian cut: {BIASED_REASON}");
    }
    write_atomic(
        &c.report.join("daylight_points.csv").to_string_lossy(),
        &points_csv(&all),
    )?;
    let count = |v: Verdict| all.iter().filter(|r| r.verdict == v).count();
    let bound = sidak_bound(c.alpha, m, None);
    println!(
        "\n{} rows: {} pass, {} flagged, {} FAIL, {} biased (approximation, not z-tested); \
         Sidak bound over {m} z-tested rows at alpha {} (normal limit {bound:.3})",
        all.len(),
        count(Verdict::Pass),
        count(Verdict::Flagged),
        count(Verdict::Fail),
        count(Verdict::Biased),
        c.alpha
    );
    anyhow::ensure!(
        count(Verdict::Fail) == 0 && count(Verdict::Flagged) == 0,
        "validate daylight: {} row(s) FAIL and {} flagged (a flagged row is not a pass); see above",
        count(Verdict::Fail),
        count(Verdict::Flagged)
    );
    println!("validate daylight: every z-tested row passed");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(estimate: f64, std_error: f64, flag: &str) -> Row {
        let exact = 100.0;
        Row {
            reference: "r".into(),
            point: "p".into(),
            p: DVec3::ZERO,
            n: DVec3::Z,
            exact,
            estimate,
            std_error,
            direct: 0.0,
            z: z_against_exact(estimate, std_error, 0.0, exact),
            bound: 3.5,
            flag: flag.into(),
            batches: 64,
            chains: 8192,
            time: 0.1,
            verdict: Verdict::Fail,
        }
    }

    #[test]
    fn a_nan_or_a_flag_is_never_a_pass_and_an_approximation_is_not_z_tested() {
        assert_eq!(judge(&row(101.0, 1.0, "ok"), false), Verdict::Pass);
        assert_eq!(judge(&row(110.0, 1.0, "ok"), false), Verdict::Fail);
        // A flag: not a pass, and no excuse for a large z.
        assert_eq!(judge(&row(101.0, 1.0, "VOV"), false), Verdict::Flagged);
        assert_eq!(judge(&row(110.0, 1.0, "VOV"), false), Verdict::Fail);
        // Not finite.
        assert_eq!(judge(&row(f64::NAN, 1.0, "ok"), false), Verdict::Fail);
        assert_eq!(judge(&row(101.0, f64::NAN, "ok"), false), Verdict::Fail);
        assert_eq!(judge(&row(f64::INFINITY, 1.0, "ok"), false), Verdict::Fail);
        // A zero error counts only when exact.
        assert_eq!(judge(&row(100.0, 0.0, "ok"), false), Verdict::Pass);
        assert_eq!(judge(&row(100.001, 0.0, "ok"), false), Verdict::Fail);
        // An approximation reports its bias, whatever its z, with its own
        // flag `approx` alone (no flag, or another, is not excused), but a
        // NaN fails.
        assert_eq!(judge(&row(110.0, 0.0, "approx"), true), Verdict::Biased);
        assert_eq!(judge(&row(110.0, 0.0, "ok"), true), Verdict::Flagged);
        assert_eq!(judge(&row(110.0, 0.0, "approx;R"), true), Verdict::Flagged);
        assert_eq!(judge(&row(f64::NAN, 0.0, "approx"), true), Verdict::Fail);
        assert_eq!(Verdict::Biased.as_str(), "biased (approximation)");
    }

    #[test]
    fn window_quadrature_against_the_unobstructed_sky() {
        // A receiver facing the window from 200 m at its mid-height sees
        // the upper half (2 x 0.6 m) of it above its horizon, a small
        // solid angle: E ~ L cos_p cos_w A / d^2 with the mean luminance of
        // that half (mean cos Z = 0.3 / 200), to about 1e-5.
        let (lz, p) = (10000.0, DVec3::new(200.0, 2.0, 1.5));
        let e = window_sky_component(lz, p, -DVec3::X);
        let d2 = 200.0f64 * 200.0;
        let approx = lz * (1.0 + 2.0 * 0.3 / 200.0) / 3.0 * 2.0 * 0.6 / d2;
        assert!((e / approx - 1.0).abs() < 1e-4, "{e} vs {approx}");
        // At window height half the opening is below the horizon; above the
        // window none of it is.
        assert_eq!(
            window_sky_component(lz, DVec3::new(1.0, 2.0, 2.5), -DVec3::X),
            0.0
        );
    }
}
