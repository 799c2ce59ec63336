//! Where no exact answer exists (a glossy Phong ceiling), the local / double
//! local estimates and the independent backward path tracer must agree within
//! their error bars, for illuminance and for luminance; the first order of
//! both against the independent reference ([`common::direct`]).

mod common;
use common::direct::{Occluder, RefLight, RefResponse, first_order};
use glam::DVec3;
use lumest::estimator::local::run;
use lumest::estimator::{Receiver, Receivers, ViewTarget, view_target};
use lumest::run::{RunConfig, Stop};
use lumest::tally::sidak_bound;

#[test]
fn local_and_backward_agree_on_a_phong_scene() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/data/sobolev_phong.toml");
    let scene = lumest::scene::load(std::path::Path::new(path)).unwrap();
    let mut rec = Vec::new();
    let mut resp = Vec::new();
    for k in 0..4 {
        let r = 0.6 * k as f64;
        rec.push(Receiver::illuminance(DVec3::new(r, 0.0, 0.0), DVec3::Z));
        rec.push(Receiver::illuminance(DVec3::new(0.0, r, 1.0), -DVec3::Z));
        resp.extend([RefResponse::Illuminance; 2]);
    }
    // Views of the glossy ceiling from the floor, and of the floor from the ceiling.
    for (o, d) in [
        (DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.3, 0.0, 1.0)),
        (DVec3::new(1.0, 0.0, 0.0), DVec3::new(-0.5, 0.2, 1.0)),
        (DVec3::new(0.5, 0.5, 0.0), DVec3::new(0.0, 0.0, 1.0)),
        (DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.4, 0.0, -1.0)),
    ] {
        let ViewTarget::Front(r) = view_target(&scene, o, d.normalize()) else {
            panic!("view misses")
        };
        // The file's materials: a Phong ceiling, a Lambertian floor.
        let wo = -d.normalize();
        resp.push(if o.z == 0.0 {
            RefResponse::Phong {
                kd: 0.3,
                ks: 0.4,
                n: 20.0,
                wo,
            }
        } else {
            RefResponse::Phong {
                kd: 0.5,
                ks: 0.0,
                n: 0.0,
                wo,
            }
        });
        rec.push(r);
    }
    let occ = [
        Occluder::Plane {
            p: DVec3::ZERO,
            n: DVec3::Z,
        },
        Occluder::Plane {
            p: DVec3::Z,
            n: -DVec3::Z,
        },
    ];
    let light = [RefLight::Point {
        q: DVec3::new(0.0, 0.0, 0.5),
        i: 1.0,
    }];
    let direct: Vec<f64> = rec
        .iter()
        .zip(&resp)
        .map(|(r, &q)| first_order(&light, &occ, r.p, r.n, q, 0))
        .collect();
    let receivers = Receivers::from_receivers(&scene, &rec).unwrap();
    let cfg = |n| RunConfig {
        seed: 21,
        stop: Stop {
            chains: Some(n),
            ..Stop::default()
        },
        ..RunConfig::default()
    };
    let local = run(&scene, &receivers, &cfg(400_000), &mut |_| true);
    let back = lumest::backward::run(&scene, &receivers, &cfg(20_000), &mut |_| true);
    let b = local.tallies.batches().min(back.tallies.batches());
    let bound = sidak_bound(1e-3, rec.len(), Some(b));
    for (j, &dj) in direct.iter().enumerate() {
        assert!(dj > 0.0, "receiver {j}: unlit");
        for (name, got) in [("local", local.direct[j]), ("backward", back.direct[j])] {
            assert!(
                (got - dj).abs() <= 1e-9 * dj,
                "receiver {j}: {name} first order {got} vs reference {dj}"
            );
        }
        // Totals: each estimator's reflected part on the reference's first order.
        let (a, c) = (&local.tallies.estimated[j], &back.tallies.estimated[j]);
        assert!(a.mean() > 0.0);
        let (ta, tc) = (dj + a.mean(), dj + c.mean());
        let z = (ta - tc) / a.std_error().hypot(c.std_error());
        assert!(
            z.abs() < bound,
            "receiver {j}: local {ta} +- {}, backward {tc} +- {} (z = {z})",
            a.std_error(),
            c.std_error()
        );
    }
}
