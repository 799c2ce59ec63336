//! Seeded mutation fuzzing of every parser (issue 12 item 16): scene TOML,
//! points and views CSV, OBJ meshes, SH coefficients, IES and EULUMDAT.
//! Each starts from a valid file of `tests/fuzz_corpus/` and applies a few
//! thousand random mutations (byte flips, deleted, repeated and truncated
//! spans, inserted tokens such as `nan`, `1e309`, `-0`, separators and
//! newlines). A parser must return (a value or an error) without
//! panicking, within a time bound, and what it accepts must be finite: a
//! scene's direct light at a test point, a table's points and intensities.

use lumest::sampling::Philox4x32;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::Instant;

const TOKENS: [&str; 16] = [
    "nan", "NaN", "inf", "-inf", "1e309", "-1e309", "1e-320", "-0", "0", "\n", ",", " ", "\"", "[",
    "]", "#",
];

fn corpus(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fuzz_corpus")
            .join(name),
    )
    .unwrap()
}

/// One random mutation of `v`.
fn mutate(v: &[u8], rng: &mut Philox4x32) -> Vec<u8> {
    let mut out = v.to_vec();
    let n = out.len().max(1);
    let pick = |rng: &mut Philox4x32, n: usize| ((rng.next_f64() * n as f64) as usize).min(n - 1);
    for _ in 0..1 + pick(rng, 3) {
        let len = out.len().max(1);
        match pick(rng, 6) {
            0 => {
                let i = pick(rng, len);
                if i < out.len() {
                    out[i] ^= 1 << pick(rng, 8);
                }
            }
            1 => {
                let i = pick(rng, len);
                let j = (i + pick(rng, 40)).min(out.len());
                if i < j {
                    out.drain(i..j);
                }
            }
            2 => {
                let i = pick(rng, len);
                let j = (i + pick(rng, 40)).min(out.len());
                if i < j {
                    let span = out[i..j].to_vec();
                    out.splice(i..i, span);
                }
            }
            3 => {
                let i = pick(rng, len).min(out.len());
                let t = TOKENS[pick(rng, TOKENS.len())];
                out.splice(i..i, t.bytes());
            }
            4 => {
                let i = pick(rng, len).min(out.len());
                out.truncate(i);
            }
            _ => {
                // Replace a number-like run with a token.
                let i = pick(rng, len);
                if i < out.len() && (out[i] as char).is_ascii_digit() {
                    let mut j = i;
                    while j < out.len() && ((out[j] as char).is_ascii_digit() || out[j] == b'.') {
                        j += 1;
                    }
                    let t = TOKENS[pick(rng, 9)];
                    out.splice(i..j, t.bytes());
                }
            }
        }
    }
    let _ = n;
    out
}

/// Run `check` on `iters` mutations of `seed_file`, written to `dir/name`;
/// panics, slow parses (over 2 s) and non-finite accepted values fail.
fn fuzz(
    dir: &Path,
    seed_file: &str,
    name: &str,
    iters: u64,
    check: &dyn Fn(&Path) -> Result<(), String>,
) {
    let base = corpus(seed_file);
    let path: PathBuf = dir.join(name);
    // The seed itself is accepted.
    std::fs::write(&path, &base).unwrap();
    assert!(
        check(&path).is_ok(),
        "{seed_file}: the valid seed fails: {:?}",
        check(&path)
    );
    let mut accepted = 0;
    for k in 0..iters {
        let mut rng = Philox4x32::new(0x00f0_220f, k ^ (seed_file.len() as u64) << 40);
        let bytes = mutate(&base, &mut rng);
        std::fs::write(&path, &bytes).unwrap();
        let t = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| check(&path)));
        let secs = t.elapsed().as_secs_f64();
        let text = String::from_utf8_lossy(&bytes);
        match r {
            Err(_) => panic!("{seed_file}: panic on mutation {k}:\n{text}"),
            Ok(Err(e)) if e.starts_with("NONFINITE") => {
                panic!("{seed_file}: {e} on mutation {k}:\n{text}")
            }
            Ok(r) => accepted += u64::from(r.is_ok()),
        }
        assert!(
            secs < 2.0,
            "{seed_file}: mutation {k} took {secs} s:\n{text}"
        );
    }
    // Both outcomes occur: the mutations reach the parser's checks.
    assert!(
        accepted > 0 && accepted < iters,
        "{seed_file}: {accepted} of {iters} accepted"
    );
}

#[test]
fn parsers_survive_mutated_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Copies the scenes may refer to.
    std::fs::write(d.join("mesh.obj"), corpus("mesh.obj")).unwrap();
    std::fs::write(d.join("table.ies"), corpus("table.ies")).unwrap();
    std::fs::write(d.join("probe.hdr"), corpus("probe.hdr")).unwrap();
    let scene_check = |p: &Path| -> Result<(), String> {
        let s = lumest::scene::load(p).map_err(|e| e.to_string())?;
        let pts = [(glam::DVec3::new(0.1, 0.2, 0.3), glam::DVec3::Z)];
        match lumest::estimator::Receivers::new(&s, &pts) {
            Ok(r) if !r.direct()[0].is_finite() => {
                Err(format!("NONFINITE direct {}", r.direct()[0]))
            }
            _ if !s.total_power().is_finite() => {
                Err(format!("NONFINITE power {}", s.total_power()))
            }
            _ => Ok(()),
        }
    };
    fuzz(d, "scene_planes.toml", "s.toml", 2000, &scene_check);
    fuzz(d, "scene_lights.toml", "s.toml", 2000, &scene_check);
    // Grids are read from a scene that compiles (as `lumest grid` does):
    // every point finite, every area positive.
    let grid_check = |p: &Path| -> Result<(), String> {
        lumest::scene::load(p).map_err(|e| e.to_string())?;
        let grids = lumest::grid::load(p).map_err(|e| e.to_string())?;
        for g in &grids {
            for q in &g.points {
                if !(q.p.is_finite() && q.n.is_finite() && q.area.is_finite() && q.area > 0.0) {
                    return Err(format!("NONFINITE grid point {q:?} in `{}`", g.name));
                }
            }
        }
        Ok(())
    };
    fuzz(d, "scene_grids.toml", "s.toml", 2000, &grid_check);
    fuzz(d, "points.csv", "p.csv", 2000, &|p| {
        let t = lumest::io::read_points(p.to_str().unwrap()).map_err(|e| e.to_string())?;
        match t
            .points
            .iter()
            .find(|(x, n)| !(x.is_finite() && n.is_finite()))
        {
            Some(bad) => Err(format!("NONFINITE point {bad:?}")),
            None => Ok(()),
        }
    });
    fuzz(d, "views.csv", "v.csv", 2000, &|p| {
        let t = lumest::io::read_views(p.to_str().unwrap()).map_err(|e| e.to_string())?;
        match t
            .views
            .iter()
            .find(|(o, v)| !(o.is_finite() && v.is_finite()))
        {
            Some(bad) => Err(format!("NONFINITE view {bad:?}")),
            None => Ok(()),
        }
    });
    fuzz(d, "mesh.obj", "m.obj", 2000, &|p| {
        lumest::geometry::mesh::Mesh::load_obj(p)
            .map(|_| ())
            .map_err(|e| e.to_string())
    });
    fuzz(d, "coeffs.csv", "c.csv", 2000, &|p| {
        let c = lumest::io::sh_coeffs::read_coefficients(p, 32).map_err(|e| e.to_string())?;
        match c.iter().find(|c| !(c.a.is_finite() && c.b.is_finite())) {
            Some(bad) => Err(format!("NONFINITE coefficient {bad:?}")),
            None => Ok(()),
        }
    });
    for (seed, name) in [("table.ies", "t.ies"), ("table.ldt", "t.ldt")] {
        fuzz(d, seed, name, 2000, &|p| {
            let ph = lumest::io::photometry::read(p).map_err(|e| e.to_string())?;
            let g = lumest::light::Goniometric::new(&ph, 1.0);
            if !g.power().is_finite() {
                return Err(format!("NONFINITE power {}", g.power()));
            }
            Ok(())
        });
    }
}
