//! Portals (issue 13 item 4): with a `[[portal]]` over the window, the
//! chains of the sky and the sun start on the window; the answer is the
//! same as without it (only the chains wasted outside are saved). A sun
//! blocked by an overhang outside the window, and light that would leave
//! through the portal, carry nothing.

use assert_cmd::Command;

fn rect(c: [f64; 3], e1: [f64; 3], e2: [f64; 3], rho: f64) -> String {
    format!(
        "[[surface]]\ntype = \"rectangle\"\ncorner = {c:?}\nedge1 = {e1:?}\nedge2 = {e2:?}\nsides = \"both\"\n\
         material = {{ type = \"lambertian\", reflectance = {rho} }}\n\n"
    )
}

/// A 4 x 4 x 3 m room with a 2 x 1.2 m window in the wall x = 0, lit by an
/// overcast sky and a low sun from the west through the window; `extra`
/// is appended (a portal, an overhang).
fn room(extra: &str) -> String {
    let mut s = String::new();
    s += &rect([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0], 0.3);
    s += &rect([0.0, 0.0, 3.0], [4.0, 0.0, 0.0], [0.0, 4.0, 0.0], 0.7);
    s += &rect([4.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 3.0], 0.5);
    s += &rect([0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 0.0, 3.0], 0.5);
    s += &rect([0.0, 4.0, 0.0], [4.0, 0.0, 0.0], [0.0, 0.0, 3.0], 0.5);
    s += &rect([0.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 0.9], 0.5);
    s += &rect([0.0, 0.0, 2.1], [0.0, 4.0, 0.0], [0.0, 0.0, 0.9], 0.5);
    s += &rect([0.0, 0.0, 0.9], [0.0, 1.0, 0.0], [0.0, 0.0, 1.2], 0.5);
    s += &rect([0.0, 3.0, 0.9], [0.0, 1.0, 0.0], [0.0, 0.0, 1.2], 0.5);
    s += "[[light]]\ntype = \"sky\"\nsky = \"overcast\"\nzenith_luminance = 10000\n\n";
    s += "[[light]]\ntype = \"sun\"\nilluminance = 50000\nsun_altitude = 30\nsun_azimuth = 270\n\n";
    s + extra
}

const PORTAL: &str = "[[portal]]\ncorner = [0, 1, 0.9]\nedge1 = [0, 2, 0]\nedge2 = [0, 0, 1.2]\n";

const POINTS: &str = "id,x,y,z,nx,ny,nz\np0,0.5,2,0.8,0,0,1\np1,1,1,0.8,0,0,1\np2,2,2,0.8,0,0,1\n\
                      p3,3,3,0.8,0,0,1\np4,3.5,0.5,0.8,0,0,1\nw,3.99,2,1.5,-1,0,0\nc,2,2,2.99,0,0,-1\n";

/// (E, stderr, R, bound on R's stderr) per point, where R = E_order1 +
/// E_rest is the reflected light, the chains' alone (no sampled direct
/// light in it), and its error is bounded by the sum of the two buckets'.
fn run(scene: &str, chains: &str, seed: &str) -> Vec<[f64; 4]> {
    let dir = tempfile::tempdir().unwrap();
    let (s, p, o) = (
        dir.path().join("s.toml"),
        dir.path().join("p.csv"),
        dir.path().join("o.csv"),
    );
    std::fs::write(&s, scene).unwrap();
    std::fs::write(&p, POINTS).unwrap();
    let out = Command::cargo_bin("lumest")
        .unwrap()
        .args([
            "illuminance",
            "--scene",
            s.to_str().unwrap(),
            "--points",
            p.to_str().unwrap(),
        ])
        .args([
            "--out",
            o.to_str().unwrap(),
            "--chains",
            chains,
            "--seed",
            seed,
            "--quiet",
            "--orders",
            "1",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&o).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (e, se) = (col("E"), col("E_stderr"));
    let (o1, o1se, r, rse) = (
        col("E_order1"),
        col("E_order1_stderr"),
        col("E_rest"),
        col("E_rest_stderr"),
    );
    lines
        .map(|l| {
            let c: Vec<f64> = l
                .split(',')
                .map(|x| x.parse().unwrap_or(f64::NAN))
                .collect();
            [c[e], c[se], c[o1] + c[r], c[o1se] + c[rse]]
        })
        .collect()
}

/// z of the difference of two estimates with their errors; 0 when both
/// are exactly equal (both exact zeros).
fn z(a: f64, sa: f64, b: f64, sb: f64) -> f64 {
    if a == b { 0.0 } else { (a - b) / sa.hypot(sb) }
}

#[test]
fn portals_change_the_cost_not_the_answer() {
    let plain = run(&room(""), "1500000", "1");
    let portal = run(&room(PORTAL), "500000", "2");
    let bound = lumest::tally::sidak_bound(0.01, 2 * plain.len(), Some(32));
    for (k, (a, b)) in plain.iter().zip(&portal).enumerate() {
        let (zt, z1) = (z(a[0], a[1], b[0], b[1]), z(a[2], a[3], b[2], b[3]));
        assert!(
            zt.abs() < bound && z1.abs() < bound,
            "point {k}: {a:?} without, {b:?} with the portal (z {zt}, {z1})"
        );
        // Reflected light reaches every point: the chains' share.
        assert!(b[2] > 0.0, "point {k}: {b:?}");
    }
    // At the back of the room (p3, p4, the wall, the ceiling) reflected
    // light is most of it: precise enough there that a portal flux 2 % off
    // fails.
    for k in [3, 4, 5, 6] {
        assert!(
            portal[k][3] < 0.02 / bound * portal[k][2],
            "point {k}: {:?}",
            portal[k]
        );
    }
}

#[test]
fn light_blocked_outside_the_portal_carries_nothing() {
    // A 3 m deep overhang over the window and side fins block the low sun
    // and most of the sky outside: with the portal the chains must notice
    // (the answer agrees with the run without a portal), not count light
    // that cannot reach the window.
    let shade = rect([-3.0, -1.0, 2.2], [3.0, 0.0, 0.0], [0.0, 6.0, 0.0], 0.0)
        + &rect([-3.0, -1.0, -1.0], [3.0, 0.0, 0.0], [0.0, 0.0, 3.2], 0.0)
        + &rect([-3.0, 5.0, -1.0], [3.0, 0.0, 0.0], [0.0, 0.0, 3.2], 0.0);
    let plain = run(&room(&shade), "600000", "3");
    let portal = run(&room(&(shade.clone() + PORTAL)), "200000", "4");
    let open = run(&room(PORTAL), "100000", "5");
    let bound = lumest::tally::sidak_bound(0.01, 2 * plain.len(), Some(32));
    for (k, (a, b)) in plain.iter().zip(&portal).enumerate() {
        let (zt, z1) = (z(a[0], a[1], b[0], b[1]), z(a[2], a[3], b[2], b[3]));
        assert!(
            zt.abs() < bound && z1.abs() < bound,
            "point {k}: {a:?} without, {b:?} with the portal (z {zt}, {z1})"
        );
        // The shading leaves the room much darker than the open window,
        // and some sky still comes in under the overhang.
        assert!(
            b[0] < 0.5 * open[k][0] && b[0] > 0.0,
            "point {k}: {b:?} shaded, {:?} open",
            open[k]
        );
    }
}

#[test]
fn a_glazed_window_with_and_without_its_portal() {
    // Clear glass in the window, and the portal in the same opening: the
    // chains that start on the portal carry the pane's transmittance (the
    // pane lies in the portal's plane); without the portal they cross it.
    let glass = "[[surface]]\ntype = \"rectangle\"\nname = \"glazing\"\ncorner = [0, 1, 0.9]\n\
                 edge1 = [0, 2, 0]\nedge2 = [0, 0, 1.2]\n\
                 material = { type = \"glass\", transmittance = 0.8 }\n\n";
    let plain = run(&room(glass), "600000", "6");
    let portal = run(&room(&(glass.to_string() + PORTAL)), "200000", "7");
    let open = run(&room(PORTAL), "100000", "8");
    let bound = lumest::tally::sidak_bound(0.01, 2 * plain.len(), Some(32));
    for (k, (a, b)) in plain.iter().zip(&portal).enumerate() {
        let (zt, z1) = (z(a[0], a[1], b[0], b[1]), z(a[2], a[3], b[2], b[3]));
        assert!(
            zt.abs() < bound && z1.abs() < bound,
            "point {k}: {a:?} without, {b:?} with the portal (z {zt}, {z1})"
        );
        // The glass passes 80 % at normal incidence, less obliquely, and
        // mirrors some of the room's light back in: between 55 % and 90 %
        // of the open window's light.
        let ratio = b[0] / open[k][0];
        assert!(
            (0.55..0.9).contains(&ratio),
            "point {k}: {b:?} glazed, {:?} open",
            open[k]
        );
    }
}
