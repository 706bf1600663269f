//! [`Trajectory`]: the points of a path a group follows ([`Group::follow`](crate::Group::follow)).

use core::fmt;

use motion_ipc::{GroupPath, MAX_GROUP_AXES, MAX_PATH_POINTS, PathFlags, PathKind, SCHEMA_VERSION};

/// What each point of a trajectory gives besides its positions; every point of one
/// trajectory gives the same.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointKind {
    /// Positions alone (the server runs a C2 spline through them, or, when that exceeds a
    /// limit, straight segments blended at the points within the group's `path_tolerance`).
    Positions,
    /// Positions and velocities (cubic segments).
    Velocities,
    /// Positions, velocities and accelerations (quintic segments).
    Accelerations,
}

impl PointKind {
    /// The [`PathFlags`] a path of such points carries.
    pub const fn flags(self) -> PathFlags {
        match self {
            Self::Positions => PathFlags(0),
            Self::Velocities => PathFlags::VELOCITIES,
            Self::Accelerations => PathFlags(PathFlags::VELOCITIES.0 | PathFlags::ACCELERATIONS.0),
        }
    }
}

impl fmt::Display for PointKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Positions => "positions only",
            Self::Velocities => "positions and velocities",
            Self::Accelerations => "positions, velocities and accelerations",
        })
    }
}

/// Why a trajectory (or a line's targets) cannot be built or sent to a group.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrajectoryError {
    /// A trajectory is for 1..=[`MAX_GROUP_AXES`] axes.
    #[error("a trajectory is for 1..={max} axes, not {axes}")]
    AxisCount {
        /// The count given to [`Trajectory::new`].
        axes: usize,
        /// [`MAX_GROUP_AXES`].
        max: usize,
    },
    /// More points than a path holds.
    #[error("a trajectory holds at most {max} points; point {point} is one too many")]
    TooManyPoints {
        /// The index the point would have had.
        point: usize,
        /// [`MAX_PATH_POINTS`].
        max: usize,
    },
    /// A point gives values for another number of axes than the trajectory has.
    #[error("point {point}: {got} {what} for a trajectory of {expected} axes")]
    WrongLength {
        /// The point's index.
        point: usize,
        /// "positions", "velocities", "accelerations".
        what: &'static str,
        /// The trajectory's axis count.
        expected: usize,
        /// How many were given.
        got: usize,
    },
    /// A point gives other quantities than the first point did.
    #[error(
        "point {point} gives {this}, but point 0 gave {first}: every point of a trajectory \
         gives the same quantities"
    )]
    MixedKinds {
        /// The point's index.
        point: usize,
        /// What point 0 gave.
        first: PointKind,
        /// What this point gives.
        this: PointKind,
    },
    /// A point's time is not finite, negative, or not after the previous point's.
    #[error("point {point}: time {time} s {}", time_problem(.previous))]
    Time {
        /// The point's index.
        point: usize,
        /// Its time, seconds from the start.
        time: f64,
        /// The previous point's time.
        previous: Option<f64>,
    },
    /// A value is NaN or infinite.
    #[error("point {point}, axis {axis}: {what} {value} is not a finite number")]
    NotFinite {
        /// The point's index.
        point: usize,
        /// The axis's index in the trajectory (the group's order).
        axis: usize,
        /// "position", "velocity", "acceleration", "scale".
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// The trajectory has no point.
    #[error("the trajectory has no points")]
    Empty,
    /// The targets or trajectory are for another number of axes than the group has.
    #[error("group {group} has {expected} axes ({axes}), but {got} values per point were given")]
    GroupAxes {
        /// The group's name.
        group: String,
        /// Its axes, comma separated, in its order.
        axes: String,
        /// The group's axis count.
        expected: usize,
        /// The count given.
        got: usize,
    },
}

fn time_problem(previous: &Option<f64>) -> String {
    match previous {
        Some(previous) => format!(
            "is not after the previous point's {previous} s (times must increase, finite, from 0 or later)"
        ),
        None => "is not a finite time of 0 or later".to_owned(),
    }
}

/// A time-parameterised path for a group: points at times (seconds from the start) with
/// a position per axis (the group's order), and optionally a velocity and an acceleration
/// per axis. Every point of one trajectory gives the same quantities.
///
/// ```
/// use motion_client::Trajectory;
///
/// let mut path = Trajectory::new(2);
/// path.push(0.5, &[10.0, 20.0])?.push(1.0, &[15.0, 25.0])?;
/// assert_eq!(path.len(), 2);
/// assert!(path.push(0.8, &[0.0, 0.0]).is_err()); // times must increase
/// # Ok::<(), motion_client::TrajectoryError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trajectory {
    axes: usize,
    kind: Option<PointKind>,
    times: Vec<f64>,
    positions: Vec<f64>,
    velocities: Vec<f64>,
    accelerations: Vec<f64>,
}

impl Trajectory {
    /// An empty trajectory for `axes` axes (the group's axis count).
    pub fn new(axes: usize) -> Self {
        Self {
            axes,
            ..Self::default()
        }
    }

    /// Axes per point.
    pub fn axes(&self) -> usize {
        self.axes
    }

    /// Points so far.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether it has no point.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// What its points give (`None` while it has none).
    pub fn kind(&self) -> Option<PointKind> {
        self.kind
    }

    /// The points' times, seconds from the start.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The positions of point `point` (the group's order).
    pub fn positions(&self, point: usize) -> Option<&[f64]> {
        Self::row(&self.positions, self.axes, point)
    }

    /// The velocities of point `point`, if the trajectory has velocities.
    pub fn velocities(&self, point: usize) -> Option<&[f64]> {
        Self::row(&self.velocities, self.axes, point)
    }

    /// The accelerations of point `point`, if the trajectory has accelerations.
    pub fn accelerations(&self, point: usize) -> Option<&[f64]> {
        Self::row(&self.accelerations, self.axes, point)
    }

    fn row(values: &[f64], axes: usize, point: usize) -> Option<&[f64]> {
        values.get(point * axes..(point + 1) * axes)
    }

    /// Adds a point with positions only.
    pub fn push(&mut self, time: f64, positions: &[f64]) -> Result<&mut Self, TrajectoryError> {
        self.add(PointKind::Positions, time, [positions, &[], &[]])
    }

    /// Adds a point with positions and velocities.
    pub fn push_with_velocities(
        &mut self,
        time: f64,
        positions: &[f64],
        velocities: &[f64],
    ) -> Result<&mut Self, TrajectoryError> {
        self.add(PointKind::Velocities, time, [positions, velocities, &[]])
    }

    /// Adds a point with positions, velocities and accelerations.
    pub fn push_full(
        &mut self,
        time: f64,
        positions: &[f64],
        velocities: &[f64],
        accelerations: &[f64],
    ) -> Result<&mut Self, TrajectoryError> {
        self.add(
            PointKind::Accelerations,
            time,
            [positions, velocities, accelerations],
        )
    }

    fn add(
        &mut self,
        kind: PointKind,
        time: f64,
        values: [&[f64]; 3],
    ) -> Result<&mut Self, TrajectoryError> {
        let point = self.len();
        if self.axes == 0 || self.axes > MAX_GROUP_AXES {
            return Err(TrajectoryError::AxisCount {
                axes: self.axes,
                max: MAX_GROUP_AXES,
            });
        }
        if point >= MAX_PATH_POINTS {
            return Err(TrajectoryError::TooManyPoints {
                point,
                max: MAX_PATH_POINTS,
            });
        }
        if let Some(first) = self.kind
            && first != kind
        {
            return Err(TrajectoryError::MixedKinds {
                point,
                first,
                this: kind,
            });
        }
        let previous = self.times.last().copied();
        if !time.is_finite() || time < 0.0 || previous.is_some_and(|previous| time <= previous) {
            return Err(TrajectoryError::Time {
                point,
                time,
                previous,
            });
        }
        let used = match kind {
            PointKind::Positions => 1,
            PointKind::Velocities => 2,
            PointKind::Accelerations => 3,
        };
        let names = [
            ("positions", "position"),
            ("velocities", "velocity"),
            ("accelerations", "acceleration"),
        ];
        for (row, (plural, singular)) in values.iter().zip(names).take(used) {
            if row.len() != self.axes {
                return Err(TrajectoryError::WrongLength {
                    point,
                    what: plural,
                    expected: self.axes,
                    got: row.len(),
                });
            }
            if let Some((axis, value)) = row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(TrajectoryError::NotFinite {
                    point,
                    axis,
                    what: singular,
                    value: *value,
                });
            }
        }
        self.kind = Some(kind);
        self.times.push(time);
        self.positions.extend_from_slice(values[0]);
        self.velocities.extend_from_slice(values[1]);
        self.accelerations.extend_from_slice(values[2]);
        Ok(self)
    }

    /// Writes the trajectory into `path` (in place: the payload is large) as path `id` of
    /// group `group`. Only the points' slots are written; the rest keeps what `path` had.
    pub fn write_into(&self, path: &mut GroupPath, group: u32, id: u64) {
        path.schema_version = SCHEMA_VERSION;
        path.kind = PathKind::Trajectory as u32;
        path.id = id;
        path.group = group;
        path.point_count = u32::try_from(self.len()).unwrap_or(u32::MAX);
        path.axis_count = u32::try_from(self.axes).unwrap_or(u32::MAX);
        path.flags = self.kind.unwrap_or(PointKind::Positions).flags().0;
        path.velocity_scale = 0.0;
        path.accel_scale = 0.0;
        for (slot, time) in path.times.iter_mut().zip(&self.times) {
            *slot = *time;
        }
        let axes = self.axes.max(1);
        let targets = [
            (&mut path.positions, &self.positions),
            (&mut path.velocities, &self.velocities),
            (&mut path.accelerations, &self.accelerations),
        ];
        for (slots, values) in targets {
            for (point, row) in values.chunks(axes).enumerate() {
                let start = point * MAX_GROUP_AXES;
                if let Some(out) = slots.get_mut(start..start + row.len()) {
                    out.copy_from_slice(row);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_are_checked_as_they_are_pushed() {
        let mut path = Trajectory::new(2);
        path.push(0.0, &[1.0, 2.0]).unwrap();
        assert!(matches!(
            path.push(0.5, &[1.0]),
            Err(TrajectoryError::WrongLength {
                point: 1,
                what: "positions",
                expected: 2,
                got: 1
            })
        ));
        assert!(matches!(
            path.push_with_velocities(0.5, &[1.0, 2.0], &[0.0, 0.0]),
            Err(TrajectoryError::MixedKinds {
                point: 1,
                first: PointKind::Positions,
                this: PointKind::Velocities
            })
        ));
        assert!(matches!(
            path.push(0.0, &[1.0, 2.0]),
            Err(TrajectoryError::Time {
                point: 1,
                previous: Some(0.0),
                ..
            })
        ));
        assert!(matches!(
            path.push(1.0, &[f64::NAN, 2.0]),
            Err(TrajectoryError::NotFinite {
                point: 1,
                axis: 0,
                what: "position",
                ..
            })
        ));
        assert_eq!(path.len(), 1, "nothing of a refused point is kept");
        assert!(matches!(
            Trajectory::new(0).push(0.0, &[]),
            Err(TrajectoryError::AxisCount { axes: 0, .. })
        ));
        assert!(matches!(
            Trajectory::new(1).push(-1.0, &[0.0]),
            Err(TrajectoryError::Time { previous: None, .. })
        ));
        let mut full = Trajectory::new(1);
        assert!(matches!(
            full.push_full(0.0, &[0.0], &[0.0], &[]),
            Err(TrajectoryError::WrongLength {
                what: "accelerations",
                ..
            })
        ));
    }

    #[test]
    fn at_most_max_path_points() {
        let mut path = Trajectory::new(1);
        for point in 0..MAX_PATH_POINTS {
            path.push(point as f64, &[0.0]).unwrap();
        }
        let error = path.push(1e9, &[0.0]).unwrap_err();
        assert_eq!(
            error,
            TrajectoryError::TooManyPoints {
                point: MAX_PATH_POINTS,
                max: MAX_PATH_POINTS
            }
        );
    }

    #[test]
    fn written_in_the_contract_layout() {
        let mut path = Trajectory::new(3);
        path.push_full(0.5, &[1.0, 2.0, 3.0], &[0.1, 0.2, 0.3], &[9.0, 8.0, 7.0])
            .unwrap()
            .push_full(1.5, &[4.0, 5.0, 6.0], &[0.0; 3], &[0.0; 3])
            .unwrap();
        let mut out = Box::new(GroupPath::EMPTY);
        path.write_into(&mut out, 2, 77);
        assert_eq!(out.kind(), Ok(PathKind::Trajectory));
        assert_eq!(
            (out.id, out.group, out.point_count, out.axis_count),
            (77, 2, 2, 3)
        );
        assert!(out.flags().contains(PathFlags::ACCELERATIONS));
        assert_eq!(&out.times[..2], &[0.5, 1.5]);
        assert_eq!(&out.positions[..3], &[1.0, 2.0, 3.0]);
        assert_eq!(
            &out.positions[MAX_GROUP_AXES..MAX_GROUP_AXES + 3],
            &[4.0, 5.0, 6.0]
        );
        assert_eq!(&out.velocities[..3], &[0.1, 0.2, 0.3]);
        assert_eq!(&out.accelerations[..3], &[9.0, 8.0, 7.0]);
        assert_eq!(path.positions(1), Some(&[4.0, 5.0, 6.0][..]));
        assert_eq!(path.velocities(2), None);
    }
}
