//! The two nearest of a set of points, in one pass: Q1 and Q2 of the search paper's BSOA
//! (the nearest obstacle points, spec 2.8) and the two nearest robots of its roaming rule
//! (eq. 5, Fig. 2). No sort and no allocation.

/// Keeps the two smallest (distance, index) pairs offered. Distances are compared strictly,
/// so of equal distances the one offered first stays ahead (offer in index order and a tie
/// keeps the lower index). Callers leave out NaN distances.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TwoNearest {
    best: [Option<(f64, usize)>; 2],
}

impl TwoNearest {
    /// Offers the point `index` at distance `d`.
    pub fn offer(&mut self, d: f64, index: usize) {
        match self.best {
            [Some(b0), _] if d < b0.0 => self.best = [Some((d, index)), Some(b0)],
            [Some(_), Some(b1)] if d >= b1.0 => {}
            [Some(_), _] => self.best[1] = Some((d, index)),
            [None, _] => self.best[0] = Some((d, index)),
        }
    }

    /// The nearest (distance, index), if any was offered.
    pub fn first(&self) -> Option<(f64, usize)> {
        self.best[0]
    }

    /// The second nearest (distance, index), if two were offered.
    pub fn second(&self) -> Option<(f64, usize)> {
        self.best[1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_two_smallest_ties_by_first_offered() {
        let mut n = TwoNearest::default();
        assert_eq!((n.first(), n.second()), (None, None));
        n.offer(5.0, 0);
        assert_eq!((n.first(), n.second()), (Some((5.0, 0)), None));
        n.offer(7.0, 1);
        n.offer(3.0, 2);
        assert_eq!((n.first(), n.second()), (Some((3.0, 2)), Some((5.0, 0))));
        // Ties keep the earlier offer, in both places.
        n.offer(3.0, 3);
        n.offer(5.0, 4);
        assert_eq!((n.first(), n.second()), (Some((3.0, 2)), Some((3.0, 3))));
        n.offer(1.0, 5);
        assert_eq!((n.first(), n.second()), (Some((1.0, 5)), Some((3.0, 2))));
    }

    #[test]
    fn matches_sorting_all() {
        let ds: Vec<f64> = (0..30).map(|i| ((i * 37) % 11) as f64).collect();
        for k in 0..ds.len() {
            let mut n = TwoNearest::default();
            let mut sorted: Vec<(f64, usize)> = ds[..k].iter().copied().zip(0..).collect();
            for &(d, i) in &sorted {
                n.offer(d, i);
            }
            sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(n.first(), sorted.first().copied(), "first {k}");
            assert_eq!(n.second(), sorted.get(1).copied(), "first {k}");
        }
    }
}
