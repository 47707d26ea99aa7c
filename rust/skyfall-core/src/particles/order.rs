//! Far-to-near order of a frame's particles, deterministic in every process.

/// Reorders `v` so that `v[j]` becomes the old `v[from[j]]` (`from` a permutation of the
/// indices), cycle by cycle, without a second buffer: a frame's streak list is megabytes, and
/// a fresh copy of it per frame costs as many page faults when the allocator hands the memory
/// back to the system between frames.
pub fn permute_in_place<T: Copy>(v: &mut [T], mut from: Vec<u32>) {
    const DONE: u32 = u32::MAX;
    for start in 0..from.len() {
        if from[start] == DONE {
            continue;
        }
        let first = v[start];
        let mut j = start;
        loop {
            let k = from[j] as usize;
            from[j] = DONE;
            if k == start {
                v[j] = first;
                break;
            }
            v[j] = v[k];
            j = k;
        }
    }
}

/// Sorts streaks far to near, ties in their given order: (key, index) pairs are a total order,
/// so the unstable sort of the small pairs gives the stable sort's order, the same in every
/// process, without moving the streaks around.
/// Its two index lists are reserved fallibly ([`crate::Error::OutOfMemory`]).
pub fn far_to_near(streaks: &mut [super::streak::ScreenStreak]) -> crate::error::Result<()> {
    use rayon::prelude::*;
    let what = "the particles' far-to-near order";
    let mut order: Vec<(f32, u32)> = crate::error::try_with_capacity(what, streaks.len())?;
    order.extend(
        streaks
            .iter()
            .enumerate()
            .map(|(i, s)| (s.inv_za + s.inv_zb, i as u32)),
    );
    order.par_sort_unstable_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
    let mut from: Vec<u32> = crate::error::try_with_capacity(what, order.len())?;
    from.extend(order.into_iter().map(|(_, i)| i));
    permute_in_place(streaks, from);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permuting_in_place_is_the_gathered_copy() {
        use rand::SeedableRng;
        use rand::seq::SliceRandom;
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        for n in [0usize, 1, 2, 7, 1000] {
            let v: Vec<u64> = (0..n as u64).map(|k| k * 7919 % 1009).collect();
            let mut from: Vec<u32> = (0..n as u32).collect();
            from.shuffle(&mut rng);
            let want: Vec<u64> = from.iter().map(|&i| v[i as usize]).collect();
            let mut got = v.clone();
            permute_in_place(&mut got, from);
            assert_eq!(got, want);
        }
    }
}
