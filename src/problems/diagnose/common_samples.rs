//! Costs of solutions whose tracked windows differ, compared over the samples all of them
//! compare.
//!
//! With sample targets every measured sample inside the tracked half cycle is compared
//! with the model. A plate's clock offset held at a value moves that plate's contact
//! events, and with them the half cycle's start or end, so solutions with different held
//! offsets compare different numbers of samples and their costs J are sums over different
//! data. On the real trial whose left plate runs 20 ms early
//! (`tests/data/real_hidden/real_clock_l-20ms`, compliant foot) the run compares 38
//! samples and, with the left clock held at −20 ms, 36: the two samples it drops carried
//! 0.037 of its J of 0.396, twice a sample's mean. A profile over J then falls towards
//! whichever offset shortens the window. Summed over the samples every solution compares,
//! the costs are comparable again.

/// A solution's data cost per compared sample: (the sample's data instant in s, what it
/// compares ([`crate::problems::track::sample_parts`]), its squared weighted data
/// residuals summed), as [`crate::problems::track::CostBreakdown`] gives them for sample
/// targets. Samples are the same when their instants and their parts are.
pub type SampleCosts = Vec<(f64, u8, f64)>;

/// Two samples whose instants differ by less than this (s) are the same sample: the
/// instants are the data's own, and samples are at least a millisecond apart.
const SAME_INSTANT_S: f64 = 1e-7;

/// What the samples common to several solutions hold.
#[derive(Debug, Clone, PartialEq)]
pub struct CommonSamples {
    /// Each solution's data cost summed over the common samples, in the order given.
    pub costs: Vec<f64>,
    /// How many samples every solution compares.
    pub samples: usize,
    /// The first and last of their instants (s); `None` when there are none.
    pub span: Option<(f64, f64)>,
}

/// The data costs of `solutions` (each one's [`SampleCosts`]) summed over the samples
/// that every one of them compares.
pub fn common_sample_costs(solutions: &[&[(f64, u8, f64)]]) -> CommonSamples {
    let sorted: Vec<Vec<(f64, u8, f64)>> = solutions
        .iter()
        .map(|s| {
            let mut v = s.to_vec();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            v
        })
        .collect();
    let cost_at = |s: &[(f64, u8, f64)], t: f64, parts: u8| -> Option<f64> {
        let i = s.partition_point(|p| p.0 < t - SAME_INSTANT_S);
        s[i..]
            .iter()
            .take_while(|p| p.0 < t + SAME_INSTANT_S)
            .find(|p| p.1 == parts)
            .map(|p| p.2)
    };
    let mut costs = vec![0.0; sorted.len()];
    let (mut samples, mut span) = (0, None::<(f64, f64)>);
    if let Some(first) = sorted.first() {
        for &(t, parts, _) in first {
            let Some(each) = sorted
                .iter()
                .map(|s| cost_at(s, t, parts))
                .collect::<Option<Vec<f64>>>()
            else {
                continue;
            };
            for (c, v) in costs.iter_mut().zip(each) {
                *c += v;
            }
            samples += 1;
            span = Some(span.map_or((t, t), |(a, _)| (a, t)));
        }
    }
    CommonSamples {
        costs,
        samples,
        span,
    }
}

#[cfg(test)]
mod tests {
    use super::common_sample_costs;

    /// Three windows over samples 10 ms apart: the run's (0–50 ms), one starting a sample
    /// later and one ending a sample earlier. Only the samples all three hold count, each
    /// solution's own costs there; the order of a solution's samples does not matter, and
    /// instants that differ by rounding alone are the same sample.
    #[test]
    fn costs_are_summed_over_the_samples_every_solution_compares() {
        let run: Vec<(f64, u8, f64)> = (0..6)
            .map(|i| (0.01 * i as f64, 7, 1.0 + i as f64))
            .collect();
        let later: Vec<(f64, u8, f64)> = (1..6)
            .rev()
            .map(|i| (0.01 * i as f64 + 1e-12, 7, 10.0 * i as f64))
            .collect();
        let earlier: Vec<(f64, u8, f64)> = (0..5).map(|i| (0.01 * i as f64, 7, 100.0)).collect();
        let c = common_sample_costs(&[&run, &later, &earlier]);
        assert_eq!(c.samples, 4);
        let (a, b) = c.span.unwrap();
        assert!(
            (a - 0.01).abs() < 1e-12 && (b - 0.04).abs() < 1e-12,
            "{:?}",
            c.span
        );
        // samples 1–4: run 2 + 3 + 4 + 5, later 10 + 20 + 30 + 40, earlier 4 × 100
        assert_eq!(c.costs, vec![14.0, 100.0, 400.0]);
        // one solution alone compares all its samples
        let alone = common_sample_costs(&[&run]);
        assert_eq!((alone.samples, alone.costs[0]), (6, 21.0));
        // disjoint windows share nothing
        let apart = common_sample_costs(&[&run[..2], &run[3..]]);
        assert_eq!((apart.samples, apart.span), (0, None));
        assert_eq!(apart.costs, vec![0.0, 0.0]);
        // an instant that compares other parts (a foot's loads moved out by a held clock)
        // is not the same sample; two samples at one instant are told apart by their parts
        let mut moved = run.clone();
        moved[2].1 = 1;
        moved.push((0.03, 2, 1000.0));
        let c = common_sample_costs(&[&run, &moved]);
        assert_eq!(c.samples, 5);
        assert_eq!(c.costs, vec![21.0 - 3.0, 21.0 - 3.0]);
    }
}
