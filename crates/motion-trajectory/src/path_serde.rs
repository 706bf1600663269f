//! Serde for [`Path`] (the engine's state snapshot, docs/ARCHITECTURE.md "The black box"):
//! its sizes and the segments in use of the active set — `count` of them, not the buffers
//! sized for the longest trajectory. The planning scratch (the draft set, cleared before
//! every plan; the spline's solve; the checker's bounds) is written and read within one
//! plan, so it is not state: a path read back gets fresh scratch. Serializing allocates nothing (the snapshot is taken in the
//! tick); reading checks every size against the others, so a damaged snapshot is refused,
//! never a panic.

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::MAX_AXES;
use crate::path::Path;
use crate::polynomial::Coeffs;
use crate::segments::Segments;

/// The most points a path read back may be sized for (a damaged size must not allocate
/// gigabytes).
const MAX_POINTS_READ: usize = 1 << 16;

#[derive(Serialize)]
struct SegmentsOut<'a> {
    count: usize,
    coeffs: &'a [Coeffs],
    starts: &'a [f64],
    lengths: &'a [f64],
    heads: &'a [usize],
    end: &'a [f64],
    duration: f64,
    max_feed: f64,
    last_point: usize,
    planned: bool,
}

#[derive(Deserialize)]
struct SegmentsIn {
    count: usize,
    coeffs: Vec<Coeffs>,
    starts: Vec<f64>,
    lengths: Vec<f64>,
    heads: Vec<usize>,
    end: Vec<f64>,
    duration: f64,
    max_feed: f64,
    last_point: usize,
    planned: bool,
}

impl<'a> SegmentsOut<'a> {
    fn of(segments: &'a Segments) -> Self {
        let (count, axes) = (segments.count, segments.axes);
        Self {
            count,
            coeffs: &segments.coeffs[..count * axes],
            starts: &segments.starts[..count],
            lengths: &segments.lengths[..count],
            heads: &segments.heads[..count],
            end: &segments.end,
            duration: segments.duration,
            max_feed: segments.max_feed,
            last_point: segments.last_point,
            planned: segments.planned,
        }
    }
}

impl SegmentsIn {
    /// Into `segments` (sized by `Path::new`), or what does not fit.
    fn restore(self, segments: &mut Segments) -> Result<(), &'static str> {
        let (count, axes) = (self.count, segments.axes);
        if count > segments.starts.len()
            || self.coeffs.len() != count * axes
            || self.starts.len() != count
            || self.lengths.len() != count
            || self.heads.len() != count
            || self.end.len() != axes
        {
            return Err("a path's segments do not match its sizes");
        }
        segments.count = count;
        segments.coeffs[..count * axes].copy_from_slice(&self.coeffs);
        segments.starts[..count].copy_from_slice(&self.starts);
        segments.lengths[..count].copy_from_slice(&self.lengths);
        segments.heads[..count].copy_from_slice(&self.heads);
        segments.end.copy_from_slice(&self.end);
        segments.duration = self.duration;
        segments.max_feed = self.max_feed;
        segments.last_point = self.last_point;
        segments.planned = self.planned;
        Ok(())
    }
}

#[derive(Serialize)]
struct PathOut<'a> {
    axes: usize,
    max_points: usize,
    active: SegmentsOut<'a>,
}

#[derive(Deserialize)]
struct PathIn {
    axes: usize,
    max_points: usize,
    active: SegmentsIn,
}

/// [`Path::serialized_bound`] of a path of `axes` axes and `max_points` points.
pub(crate) fn serialized_bound_of(axes: usize, max_points: usize) -> usize {
    let capacity = 2 * max_points + 3;
    // varints of usize: 10 bytes; f64: 8; a slice: its length's varint and its items.
    let slice = |items: usize, item: usize| 10 + items * item;
    4 * 10
        + slice(capacity * axes, 6 * 8)
        + 2 * slice(capacity, 8)
        + slice(capacity, 10)
        + slice(axes, 8)
        + 2 * 8
        + 10
        + 1
}

impl Path {
    /// Bytes this path takes serialized at the most (its longest trajectory planned): what
    /// a snapshot buffer must hold for it.
    pub fn serialized_bound(&self) -> usize {
        serialized_bound_of(self.axes, self.max_points)
    }
}

impl Serialize for Path {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        PathOut {
            axes: self.axes,
            max_points: self.max_points,
            active: SegmentsOut::of(&self.active),
        }
        .serialize(serializer)
    }
}

impl<'de> Deserialize<'de> for Path {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let wire = PathIn::deserialize(deserializer)?;
        if !(1..=MAX_AXES).contains(&wire.axes) || wire.max_points > MAX_POINTS_READ {
            return Err(D::Error::custom(format!(
                "a path of {} axes and {} points",
                wire.axes, wire.max_points
            )));
        }
        let mut path = Path::new(wire.axes, wire.max_points);
        wire.active
            .restore(&mut path.active)
            .map_err(D::Error::custom)?;
        Ok(path)
    }
}

/// Serde for a path that is planning scratch only (`#[serde(with =
/// "motion_trajectory::serde_scratch_path")]`: a group's spare path, planned into and
/// swapped with the running one within one request, never read otherwise): its sizes
/// alone, read back as an empty path of those sizes.
pub mod scratch {
    use serde::de::Error as _;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    use super::MAX_POINTS_READ;
    use crate::{MAX_AXES, Path};

    /// Writes `path`'s axes and points.
    pub fn serialize<S: Serializer>(path: &Path, serializer: S) -> Result<S::Ok, S::Error> {
        (path.axes, path.max_points).serialize(serializer)
    }

    /// An empty path of the sizes written.
    pub fn deserialize<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Path, D::Error> {
        let (axes, max_points) = <(usize, usize)>::deserialize(deserializer)?;
        if !(1..=MAX_AXES).contains(&axes) || max_points > MAX_POINTS_READ {
            return Err(D::Error::custom(format!(
                "a path of {axes} axes and {max_points} points"
            )));
        }
        Ok(Path::new(axes, max_points))
    }
}

#[cfg(test)]
mod tests {
    use crate::{AxisLimits, Path};

    fn limits() -> [AxisLimits; 2] {
        [AxisLimits {
            min: -100.0,
            max: 100.0,
            max_velocity: 50.0,
            max_accel: 200.0,
        }; 2]
    }

    #[test]
    fn a_planned_path_reads_back_and_samples_the_same() {
        let mut path = Path::new(2, 64);
        path.plan_line(&[0.0, 0.0], &[10.0, -5.0], &limits(), 1.0, 1.0)
            .expect("a line plans");
        let bytes = postcard::to_allocvec(&path).expect("serializes");
        // The segments in use, not the buffers for 64 points.
        assert!(bytes.len() < 2000, "{} bytes", bytes.len());
        let back: Path = postcard::from_bytes(&bytes).expect("reads back");
        assert_eq!(postcard::to_allocvec(&back).expect("serializes"), bytes);
        for i in 0..=40 {
            let t = path.duration() * f64::from(i) / 40.0;
            let mut a = [[0.0; 2]; 3];
            let mut b = [[0.0; 2]; 3];
            let [pa, va, aa] = &mut a;
            let [pb, vb, ab] = &mut b;
            path.sample(t, pa, va, aa);
            back.sample(t, pb, vb, ab);
            assert_eq!(a, b, "at {t}");
        }
    }

    #[test]
    fn the_bound_holds_the_longest_trajectory() {
        let (axes, points) = (2, 40);
        let mut path = Path::new(axes, points);
        let times: Vec<f64> = (1..=points).map(|i| i as f64 * 0.5).collect();
        let positions: Vec<f64> = (0..points * axes)
            .map(|i| ((i * 7919) % 5) as f64 - 2.0)
            .collect();
        let zeros = vec![0.0; points * axes];
        let trajectory = crate::Points {
            times: &times,
            positions: &positions,
            velocities: Some(&zeros),
            accelerations: Some(&zeros),
            stride: axes,
        };
        let tolerances = crate::Tolerances {
            start: &[1e-6; 2],
            path: &[0.0; 2],
        };
        path.plan_points(
            &[0.0; 2],
            &[0.0; 2],
            &[0.0; 2],
            &trajectory,
            &limits(),
            &tolerances,
        )
        .expect("plans");
        let len = postcard::to_allocvec(&path).expect("serializes").len();
        assert!(len > 1000, "{len} bytes: the trajectory is planned");
        assert!(len <= path.serialized_bound(), "{len} bytes");
    }

    #[test]
    fn a_scratch_path_is_its_sizes() {
        #[derive(serde::Serialize, serde::Deserialize)]
        struct Holder {
            #[serde(with = "super::scratch")]
            path: Path,
        }
        let mut holder = Holder {
            path: Path::new(2, 64),
        };
        holder
            .path
            .plan_line(&[0.0, 0.0], &[10.0, -5.0], &limits(), 1.0, 1.0)
            .expect("a line plans");
        let bytes = postcard::to_allocvec(&holder).expect("serializes");
        assert_eq!(bytes, [2, 64]);
        let back: Holder = postcard::from_bytes(&bytes).expect("reads back");
        assert_eq!((back.path.axes(), back.path.duration()), (2, 0.0));
        assert!(postcard::from_bytes::<Holder>(&[0, 64]).is_err());
    }

    #[test]
    fn a_damaged_path_is_refused() {
        let mut path = Path::new(2, 8);
        path.plan_line(&[0.0, 0.0], &[1.0, 1.0], &limits(), 1.0, 1.0)
            .expect("a line plans");
        let mut bytes = postcard::to_allocvec(&path).expect("serializes");
        // axes = 0, then a count larger than the buffers.
        bytes[0] = 0;
        assert!(postcard::from_bytes::<Path>(&bytes).is_err());
        let mut bytes = postcard::to_allocvec(&path).expect("serializes");
        bytes[2] = 100;
        assert!(postcard::from_bytes::<Path>(&bytes).is_err());
    }
}
