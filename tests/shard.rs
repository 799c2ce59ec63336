//! Sharded runs: `lumest illuminance ... --shard I/M --out PART` and
//! `lumest merge PART... --out R.csv` give the single run's CSV byte for
//! byte, and mismatched, missing, repeated or damaged shards are refused.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

fn data(f: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(f)
        .to_string_lossy()
        .into_owned()
}

fn lumest(args: &[&str]) -> std::process::Output {
    Command::cargo_bin("lumest")
        .unwrap()
        .args(args)
        .output()
        .unwrap()
}

/// One whole run and its shards (each with its own thread count), merged
/// in a scrambled order; returns (whole CSV, merged CSV).
fn whole_and_merged(
    scene: &str,
    points: &str,
    extra: &[&str],
    m: u64,
    dir: &Path,
) -> (Vec<u8>, Vec<u8>) {
    let full = dir.join("full.csv");
    let mut args = vec![
        "illuminance",
        "--scene",
        scene,
        "--points",
        points,
        "--quiet",
    ];
    args.extend(extra);
    let f = full.to_str().unwrap();
    let mut a = args.clone();
    a.extend(["--out", f, "--threads", "2"]);
    let o = lumest(&a);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut parts: Vec<PathBuf> = Vec::new();
    for i in 0..m {
        let p = dir.join(format!("part{i}.state"));
        let shard = format!("{i}/{m}");
        let threads = (1 + i % 3).to_string();
        let mut a = args.clone();
        a.extend([
            "--shard",
            &shard,
            "--out",
            p.to_str().unwrap(),
            "--threads",
            &threads,
        ]);
        let o = lumest(&a);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        parts.push(p);
    }
    // Any order: last, first, then the rest.
    parts.rotate_right(1);
    let merged = dir.join("merged.csv");
    let mut a = vec!["merge".to_string()];
    a.extend(parts.iter().map(|p| p.to_string_lossy().into_owned()));
    a.extend(["--out".to_string(), merged.to_string_lossy().into_owned()]);
    let a: Vec<&str> = a.iter().map(String::as_str).collect();
    let o = lumest(&a);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (std::fs::read(full).unwrap(), std::fs::read(merged).unwrap())
}

#[test]
fn merged_shards_are_the_single_run_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    // Two planes, resolved orders, an uneven shard count.
    let (full, merged) = whole_and_merged(
        &data("sobolev.toml"),
        &data("sobolev_points.csv"),
        &["--chains", "30000", "--seed", "11", "--orders", "2"],
        3,
        dir.path(),
    );
    assert!(full.len() > 1000);
    assert!(
        full == merged,
        "sharded Sobolev run differs from the single run"
    );
    // The furnished office: luminaires, a mesh, the near/far split where
    // needed, more shards than threads.
    let (full, merged) = whole_and_merged(
        &data("office.toml"),
        &data("office_grid.csv"),
        &["--chains", "20000", "--seed", "3"],
        5,
        dir.path(),
    );
    assert!(
        full == merged,
        "sharded office run differs from the single run"
    );
    // Points listed planar up and cylindrical at one position: the
    // modelling ratio's columns, whose errors need the batch means the
    // merge folds again.
    let pairs = dir.path().join("pairs.csv");
    std::fs::write(
        &pairs,
        "x,y,z,nx,ny,nz,receiver\n\
         0.5,0,0.3,0,0,1,planar\n\
         0.5,0,0.3,0,0,1,cylindrical\n\
         1.5,1,0.6,0,0,1,\n\
         1.5,1,0.6,0,0,-1,cylindrical\n\
         2,0,0.5,1,0,0,planar\n",
    )
    .unwrap();
    let (full, merged) = whole_and_merged(
        &data("sobolev.toml"),
        pairs.to_str().unwrap(),
        &["--chains", "20000", "--seed", "5"],
        3,
        dir.path(),
    );
    let text = String::from_utf8_lossy(&full);
    assert!(text.contains("modelling_ratio"), "{text}");
    // Reflected light: both pairs' ratios carry a positive error.
    let head: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let cs = head
        .iter()
        .position(|h| *h == "modelling_ratio_stderr")
        .unwrap();
    for k in [2, 4] {
        let se: f64 = text
            .lines()
            .nth(k)
            .unwrap()
            .split(',')
            .nth(cs)
            .unwrap()
            .parse()
            .unwrap();
        assert!(se > 0.0, "row {k}: {se}");
    }
    assert!(full == merged, "sharded run with modelling pairs differs");
    // The backward estimator, one shard (the whole run in one state).
    let (full, merged) = whole_and_merged(
        &data("sobolev.toml"),
        &data("sobolev_points.csv"),
        &["--chains", "4000", "--seed", "2", "--estimator", "backward"],
        1,
        dir.path(),
    );
    assert!(full == merged, "backward run through one shard differs");
    // The scene set up as a single run sets it up: the direct light
    // sampled (`--direct-lights ris`), and a light at infinity over an
    // infinite plane, whose start density is fitted to the points. (A
    // shard that skipped either read about 0.3 % and 2.5 % off.)
    let (full, merged) = whole_and_merged(
        &data("office.toml"),
        &data("office_grid.csv"),
        &["--chains", "8000", "--seed", "3", "--direct-lights", "ris"],
        2,
        dir.path(),
    );
    assert!(full == merged, "sharded office run with RIS differs");
    let (full, merged) = whole_and_merged(
        &data("sun_floor.toml"),
        &data("sun_floor_points.csv"),
        &["--chains", "8000", "--seed", "4"],
        2,
        dir.path(),
    );
    assert!(full == merged, "sharded run under the sun differs");
    // A scene that emits nothing: the shards hold no batch, and the merge
    // writes the single run's exact zeros (flagged `ok`, not `batches`).
    let dark = dir.path().join("dark.toml");
    std::fs::write(
        &dark,
        "[[surface]]\ntype = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n\
         material = { type = \"lambertian\", reflectance = 0.5 }\n\
         [[light]]\ntype = \"point\"\nposition = [0.0, 0.0, 2.0]\nflux = 0.0\n",
    )
    .unwrap();
    let (full, merged) = whole_and_merged(
        dark.to_str().unwrap(),
        &data("sobolev_points.csv"),
        &["--chains", "1000"],
        2,
        dir.path(),
    );
    assert!(String::from_utf8_lossy(&full).contains(",ok\n"));
    assert!(full == merged, "sharded dark run differs");
}

/// Writes shard `i/m` of a Sobolev run with `seed` (and `extra`) to `name`.
fn shard(dir: &Path, name: &str, i: u64, m: u64, seed: &str, scene: &str) -> String {
    let p = dir.join(name).to_string_lossy().into_owned();
    let s = format!("{i}/{m}");
    let o = lumest(&[
        "illuminance",
        "--scene",
        &data(scene),
        "--points",
        &data("sobolev_points.csv"),
        "--chains",
        "8000",
        "--seed",
        seed,
        "--shard",
        &s,
        "--out",
        &p,
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    p
}

/// The office scene and the files it names, with its work-plane points.
const OFFICE_FILES: [&str; 5] = [
    "office.toml",
    "office_grid.csv",
    "blob.obj",
    "downlight.ldt",
    "pendant.ies",
];

/// A copy of [`OFFICE_FILES`] in `dir/sc`; returns that folder.
fn office_copy(dir: &Path) -> PathBuf {
    let sc = dir.join("sc");
    std::fs::create_dir(&sc).unwrap();
    for f in OFFICE_FILES {
        std::fs::copy(data(f), sc.join(f)).unwrap();
    }
    sc
}

/// Shard 0/1 of a 1000-chain run of the office copy in `sc`, its state to
/// `out`.
fn office_shard(sc: &Path, out: &str) -> std::process::Output {
    lumest(&[
        "illuminance",
        "--scene",
        sc.join("office.toml").to_str().unwrap(),
        "--points",
        sc.join("office_grid.csv").to_str().unwrap(),
        "--chains",
        "1000",
        "--shard",
        "0/1",
        "--out",
        out,
        "--quiet",
    ])
}

/// FNV-1a 64, the states' documented checksum (written out here from its
/// definition).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h: u64, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

fn merge_err(parts: &[&str], out: &Path) -> String {
    let mut a = vec!["merge"];
    a.extend(parts);
    let out = out.to_str().unwrap();
    a.extend(["--out", out]);
    let o = lumest(&a);
    assert!(!o.status.success(), "merge of {parts:?} was accepted");
    assert!(!Path::new(out).exists(), "a refused merge wrote {out}");
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn mismatched_missing_repeated_or_damaged_shards_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("r.csv");
    let a0 = shard(d, "a0", 0, 2, "1", "sobolev.toml");
    let a1 = shard(d, "a1", 1, 2, "1", "sobolev.toml");
    let seed2 = shard(d, "b1", 1, 2, "2", "sobolev.toml");
    let other = shard(d, "c1", 1, 2, "1", "sobolev_phong.toml");
    let e = merge_err(&[&a0, &seed2], &out);
    assert!(e.contains("different runs") && e.contains("seeds"), "{e}");
    let e = merge_err(&[&a0, &other], &out);
    assert!(e.contains("different runs") && e.contains("scenes"), "{e}");
    let e = merge_err(&[&a0], &out);
    assert!(e.contains("shard(s) 1/2 of the run are missing"), "{e}");
    let e = merge_err(&[&a0, &a1, &a1], &out);
    assert!(e.contains("both shard 1/2"), "{e}");
    // A cut file and a flipped byte.
    let bytes = std::fs::read(&a1).unwrap();
    let cut = d.join("cut").to_string_lossy().into_owned();
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    let e = merge_err(&[&a0, &cut], &out);
    assert!(e.contains("cut") && e.contains("damaged"), "{e}");
    let mut flipped = bytes.clone();
    let k = flipped.len() / 2;
    flipped[k] ^= 1;
    std::fs::write(&cut, &flipped).unwrap();
    let e = merge_err(&[&a0, &cut], &out);
    assert!(e.contains("checksum"), "{e}");
    // A header edited by hand, its checksum made good: refused with the
    // field named, not a crash.
    let text_end = bytes.windows(2).position(|w| w == b"\n\n").unwrap();
    let header = String::from_utf8(bytes[..text_end].to_vec()).unwrap();
    for (from, to, want) in [
        ("shard = 1/2", "shard = 5/2", "shard 5/2"),
        ("shard = 1/2", "shard = 0/0", "shard 0/0"),
        (
            "shard = 1/2",
            "shard = 1/99999999999999",
            "shard 1/99999999999999",
        ),
        ("orders = 0", "orders = 2", "sums"),
    ] {
        assert!(header.contains(from), "{header}");
        let mut edited = header.replace(from, to).into_bytes();
        edited.extend(&bytes[text_end..bytes.len() - 8]);
        let sum = fnv1a(&edited);
        edited.extend(sum.to_le_bytes());
        std::fs::write(&cut, &edited).unwrap();
        let e = merge_err(&[&a0, &cut], &out);
        assert!(
            e.contains("not a shard state lumest writes")
                && e.contains(want)
                && !e.contains("panicked"),
            "{to}: {e}"
        );
    }
    // A CSV is not a shard.
    let e = merge_err(&[&a0, &data("sobolev_points.csv")], &out);
    assert!(e.contains("not a lumest shard state"), "{e}");
    // The good pair merges.
    let o = lumest(&["merge", &a1, &a0, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn shard_options_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p").to_string_lossy().into_owned();
    let base = [
        "illuminance",
        "--scene",
        &data("sobolev.toml"),
        "--points",
        &data("sobolev_points.csv"),
        "--out",
        &p,
    ];
    for (extra, want) in [
        (vec!["--shard", "0/2"], "--chains"),
        (vec!["--shard", "2/2", "--chains", "1000"], "0 <= I < M"),
        (vec!["--shard", "0/0", "--chains", "1000"], "0 <= I < M"),
        (vec!["--shard", "a", "--chains", "1000"], "I/M"),
        (
            vec!["--shard", "0/2", "--chains", "1000", "--time", "1"],
            "--time",
        ),
        // The merge writes no daylight-factor columns: refused, not dropped.
        (
            vec!["--shard", "0/2", "--chains", "1000", "--daylight-factor"],
            "--daylight-factor",
        ),
    ] {
        let mut a = base.to_vec();
        a.extend(extra.iter());
        let o = lumest(&a);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{extra:?}: {e}");
        assert!(!Path::new(&p).exists());
    }
    // A binary state on standard output, which `merge` cannot read.
    let mut a = base.to_vec();
    a[6] = "-";
    a.extend(["--shard", "0/2", "--chains", "1000"]);
    let o = lumest(&a);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("not `-`") && o.stdout.is_empty(),
        "{e}"
    );
    // What a single run refuses, a shard refuses too: glass panes with
    // the backward estimator or a fixed near part.
    for (scene, points, extra, want) in [
        (
            "office_daylight.toml",
            "office_grid.csv",
            ["--estimator", "backward"],
            "glass panes",
        ),
        (
            "office_daylight.toml",
            "office_grid.csv",
            ["--near-radius", "0.1"],
            "--near-radius do not support",
        ),
    ] {
        let (scene, points) = (data(scene), data(points));
        let mut a = vec![
            "illuminance",
            "--scene",
            &scene,
            "--points",
            &points,
            "--out",
            &p,
        ];
        a.extend(["--shard", "0/1", "--chains", "1000"]);
        a.extend(extra);
        let o = lumest(&a);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && e.contains(want), "{extra:?}: {e}");
        assert!(!Path::new(&p).exists());
    }
    // A shard's state never goes over a file the scene names.
    let sc = office_copy(dir.path());
    let ies = sc.join("pendant.ies");
    let before = std::fs::read(&ies).unwrap();
    let o = office_shard(&sc, ies.to_str().unwrap());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("overwrite the input"),
        "{e}"
    );
    assert_eq!(std::fs::read(&ies).unwrap(), before);
    // A points column named like a result column, refused by a shard as by
    // a single run (the merge would write it twice).
    let pts = dir.path().join("pts.csv");
    std::fs::write(&pts, "x,y,z,nx,ny,nz,modelling_ratio\n1,0,0,0,0,1,3\n").unwrap();
    let o = lumest(&[
        "illuminance",
        "--scene",
        &data("sobolev.toml"),
        "--points",
        pts.to_str().unwrap(),
        "--out",
        &p,
        "--shard",
        "0/2",
        "--chains",
        "1000",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("`modelling_ratio` has the name of a result column"),
        "{e}"
    );
    assert!(!Path::new(&p).exists());
}

/// Two scenes that differ only inside a mesh file (one vertex moved, the
/// same counts and bounds): their shards are different runs. The old build
/// named a mesh in the scene's hash by its counts and bounds alone and
/// merged them into a result neither scene gives.
#[test]
fn shards_of_scenes_whose_meshes_differ_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut parts = Vec::new();
    for (k, z) in [(0u64, "0.6"), (1, "0.65")] {
        let sub = d.join(format!("s{k}"));
        std::fs::create_dir(&sub).unwrap();
        // A tent over a 2 x 2 m square, apex 0.8 m: one vertex on its front
        // slope differs in height (the bounds and counts are the same).
        let obj = format!(
            "v -1 -1 0.5\nv 1 -1 0.5\nv 1 1 0.5\nv -1 1 0.5\nv 0 0 0.8\nv 0 -0.5 {z}\n\
             f 1 2 6\nf 2 5 6\nf 6 5 1\nf 2 3 5\nf 3 4 5\nf 4 1 5\n"
        );
        std::fs::write(sub.join("tent.obj"), obj).unwrap();
        std::fs::write(
            sub.join("t.toml"),
            "[[surface]]\nname = \"floor\"\ntype = \"plane\"\npoint = [0, 0, 0]\nnormal = [0, 0, 1]\n\
             material = { type = \"lambertian\", reflectance = 0.5 }\n\n\
             [[surface]]\nname = \"tent\"\ntype = \"mesh\"\nfile = \"tent.obj\"\n\
             material = { type = \"lambertian\", reflectance = 0.5 }\n\n\
             [[light]]\ntype = \"point\"\nposition = [0, 0, 3]\nintensity = 100\n",
        )
        .unwrap();
        std::fs::write(
            sub.join("p.csv"),
            "x,y,z,nx,ny,nz\n0,0,0.65,0,0,1\n2,0,0,0,0,1\n",
        )
        .unwrap();
        let p = d.join(format!("part{k}")).to_string_lossy().into_owned();
        let o = lumest(&[
            "illuminance",
            "--scene",
            sub.join("t.toml").to_str().unwrap(),
            "--points",
            sub.join("p.csv").to_str().unwrap(),
            "--chains",
            "4000",
            "--shard",
            &format!("{k}/2"),
            "--out",
            &p,
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        parts.push(p);
    }
    let e = merge_err(&[&parts[0], &parts[1]], &d.join("r.csv"));
    assert!(e.contains("different runs") && e.contains("scenes"), "{e}");
}

/// A state names the build that wrote it (its git commit, `+dirty` with
/// changed tracked files, `unknown` outside a checkout): shards and
/// checkpoints of different builds, whose numbers need not agree bit for
/// bit, are different runs. The old build named only the crate's version,
/// and merged shards of two commits that changed the numbers.
#[test]
fn states_name_their_build() {
    let dir = tempfile::tempdir().unwrap();
    let part = shard(dir.path(), "p0", 0, 2, "1", "sobolev.toml");
    let bytes = std::fs::read(&part).unwrap();
    let end = bytes.windows(2).position(|w| w == b"\n\n").unwrap();
    let header = String::from_utf8(bytes[..end].to_vec()).unwrap();
    let config = header.lines().find(|l| l.starts_with("config = ")).unwrap();
    let id = config
        .split(" build ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or_else(|| panic!("no build in {config}"));
    let commit = id.strip_suffix("+dirty").unwrap_or(id);
    assert!(
        id == "unknown" || (commit.len() == 40 && commit.chars().all(|c| c.is_ascii_hexdigit())),
        "{id}"
    );
}

/// `lumest merge --out` never writes over the run's own inputs (the scene,
/// the points, a file the scene names, one reached by a symbolic link),
/// which the shards record; a state without that record (an edited header,
/// its checksum made good) still merges.
#[test]
fn merge_never_writes_over_the_runs_inputs() {
    let dir = tempfile::tempdir().unwrap();
    let sc = office_copy(dir.path());
    let part = dir.path().join("part").to_string_lossy().into_owned();
    let o = office_shard(&sc, &part);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let link = dir.path().join("link.ies");
    std::os::unix::fs::symlink(sc.join("pendant.ies"), &link).unwrap();
    let targets = OFFICE_FILES.iter().map(|f| sc.join(f)).chain([link]);
    for out in targets {
        let before = std::fs::read(&out).unwrap();
        let o = lumest(&["merge", &part, "--out", out.to_str().unwrap()]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && e.contains("would overwrite the input"),
            "{}: {e}",
            out.display()
        );
        assert_eq!(std::fs::read(&out).unwrap(), before, "{}", out.display());
    }
    // Without the record (a state written before it), the merge goes on.
    let bytes = std::fs::read(&part).unwrap();
    let end = bytes.windows(2).position(|w| w == b"\n\n").unwrap();
    let header = String::from_utf8(bytes[..end].to_vec()).unwrap();
    assert!(header.contains("\ninputs = "), "{header}");
    let kept: Vec<&str> = header
        .lines()
        .filter(|l| !l.starts_with("inputs = "))
        .collect();
    let mut edited = kept.join("\n").into_bytes();
    edited.extend(&bytes[end..bytes.len() - 8]);
    let sum = fnv1a(&edited);
    edited.extend(sum.to_le_bytes());
    let old = dir.path().join("old").to_string_lossy().into_owned();
    std::fs::write(&old, &edited).unwrap();
    let (r1, r2) = (dir.path().join("r1.csv"), dir.path().join("r2.csv"));
    for (p, r) in [(&part, &r1), (&old, &r2)] {
        let o = lumest(&["merge", p, "--out", r.to_str().unwrap()]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{e}");
        // (The summary once said the merge ran "on 0 thread(s)".)
        assert!(!e.contains("0 thread(s)"), "{e}");
    }
    assert_eq!(std::fs::read(&r1).unwrap(), std::fs::read(&r2).unwrap());
}
