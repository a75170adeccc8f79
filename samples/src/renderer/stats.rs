//! Per-frame GPU times gathered from handed-back tickets and the sample's own timestamps.
/// Mean GPU times over the frames after the first (which builds every BLAS).
#[derive(Default, Debug, Clone)]
pub struct Stats {
    /// (label, ms per frame), in scheduling order; a label's tasks of one frame are summed
    /// (the debug views run only in frames that ask for them).
    pub sdk: Vec<(String, Vec<f64>)>,
    /// ("task label: pass", ms per frame) of the denoisers' passes (`--time-passes`).
    pub sdk_passes: Vec<(String, Vec<f64>)>,
    pub passes: Vec<(String, Vec<f64>)>,
    pub first_frame_bvh_ms: f64,
    pub frames: u64,
}

impl Stats {
    pub(super) fn add(list: &mut Vec<(String, Vec<f64>)>, frame_values: Vec<(String, f64)>) {
        for (k, v) in frame_values {
            match list.iter_mut().find(|(l, _)| *l == k) {
                Some((_, values)) => values.push(v),
                None => list.push((k, vec![v])),
            }
        }
    }

    /// (label, mean ms) of the SDK's tasks and of the sample's own passes.
    pub fn means(list: &[(String, Vec<f64>)]) -> Vec<(String, f64)> {
        list.iter().map(|(l, v)| (l.clone(), v.iter().sum::<f64>() / v.len().max(1) as f64)).collect()
    }
}
