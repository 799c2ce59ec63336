//! Collisions held for the open kernel and scored a block of receivers at
//! a time (`Receivers::score_held`, the batch loop's path) give every
//! receiver the same bits as scoring each collision at once
//! (`Receivers::score`): lists longer than a block on both Sobolev planes,
//! order buckets, counted and uncounted chains.

use lumest::cases::sobolev::sobolev_case;
use lumest::chain::{self, ChainParams};
use lumest::estimator::Receivers;
use lumest::reference::Sobolev;
use lumest::sampling::Philox4x32;

#[test]
fn held_scores_give_the_bits_of_scores_at_once() {
    let s = Sobolev::new(0.5, 0.5, 0.7, 0.6, 1.0).unwrap();
    let case = sobolev_case(&s, 9000, 3.0);
    let scene = &case.scene;
    let rec = Receivers::new(scene, &case.points).unwrap();
    let len = rec.accumulator_len();
    let buckets = 3;
    let mut now = vec![0.0; (buckets + 1) * len];
    let mut held_acc = now.clone();
    let mut held = rec.new_hold();
    let (mut scores_now, mut scores_held) = (0, 0);
    for c in 0..300u64 {
        let mut rng = Philox4x32::new(5, c);
        let u = [rng.next_2d(), rng.next_2d()];
        let counting = c % 8 == 0;
        chain::trace(scene, &mut rng, &ChainParams::default(), u, |col| {
            let k = (col.order.max(1) as usize - 1).min(buckets - 1);
            let (acc, near) = now.split_at_mut(buckets * len);
            let near = counting.then_some(near);
            scores_now += rec.score(scene, col, &mut acc[k * len..(k + 1) * len], near);
            scores_held += rec.score_held(scene, col, k, &mut held_acc, counting, &mut held);
        });
    }
    rec.flush_held(&mut held, &mut held_acc);
    assert_eq!(scores_now, scores_held);
    assert!(scores_now > 1_000_000, "{scores_now} scores");
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert!(
        now.iter().filter(|&&x| x > 0.0).count() > len,
        "the buckets were scored into"
    );
    assert!(
        now[buckets * len..].iter().any(|&x| x > 0.0),
        "some scores were counted"
    );
    assert_eq!(bits(&now), bits(&held_acc));
}
