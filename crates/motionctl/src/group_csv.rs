//! The CSV of `motionctl group follow`: a header `time,<axis>,…` with optional
//! `<axis>:vel` and `<axis>:acc` columns, then one row per point (time in seconds from the
//! start). Every group axis has a position column; velocities for every axis or none;
//! accelerations only with velocities (and then for every axis). Blank lines and lines
//! starting with `#` are skipped. Every error names its line.

use core::fmt;

use motion_client::{Trajectory, TrajectoryError};

/// A CSV problem and the line (from 1) it is on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CsvError {
    /// The line, counted from 1.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for CsvError {}

fn error(line: usize, message: impl Into<String>) -> CsvError {
    CsvError {
        line,
        message: message.into(),
    }
}

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Column {
    Time,
    /// (quantity: 0 position, 1 velocity, 2 acceleration; the axis's slot in the group)
    Value(usize, usize),
}

/// Per quantity: the column suffix and the plural.
const QUANTITIES: [(&str, &str); 3] = [
    ("", "positions"),
    (":vel", "velocities"),
    (":acc", "accelerations"),
];

/// The columns of `header` (line `line`) for a group of `axes`, and how many quantities
/// (1, 2 or 3) every point gives.
fn columns(header: &str, line: usize, axes: &[String]) -> Result<(Vec<Column>, usize), CsvError> {
    let mut columns = Vec::new();
    let mut seen = vec![[false; 3]; axes.len()];
    let mut time = false;
    for name in header.split(',').map(str::trim) {
        if name == "time" {
            if time {
                return Err(error(line, "column `time` appears twice"));
            }
            time = true;
            columns.push(Column::Time);
            continue;
        }
        let (axis, quantity) = match name.split_once(':') {
            None => (name, 0),
            Some((axis, "vel")) => (axis, 1),
            Some((axis, "acc")) => (axis, 2),
            Some((_, other)) => {
                return Err(error(
                    line,
                    format!("column `{name}`: `:{other}` is neither `:vel` nor `:acc`"),
                ));
            }
        };
        let Some(slot) = axes.iter().position(|a| a == axis) else {
            return Err(error(
                line,
                format!(
                    "column `{name}`: `{axis}` is not an axis of the group (its axes: {})",
                    axes.join(", ")
                ),
            ));
        };
        if std::mem::replace(&mut seen[slot][quantity], true) {
            return Err(error(line, format!("column `{name}` appears twice")));
        }
        columns.push(Column::Value(quantity, slot));
    }
    if !time {
        return Err(error(
            line,
            "no `time` column (the header is `time,<axis>,…`)",
        ));
    }
    let missing = |quantity: usize| -> Vec<String> {
        axes.iter()
            .zip(&seen)
            .filter(|(_, seen)| !seen[quantity])
            .map(|(axis, _)| format!("{axis}{}", QUANTITIES[quantity].0))
            .collect()
    };
    let positions = missing(0);
    if !positions.is_empty() {
        return Err(error(
            line,
            format!(
                "every axis of the group needs a position column; missing: {}",
                positions.join(", ")
            ),
        ));
    }
    let mut quantities = 1;
    for (quantity, (_, plural)) in QUANTITIES.iter().enumerate().skip(1) {
        let absent = missing(quantity);
        if absent.len() == axes.len() {
            continue;
        }
        if !absent.is_empty() {
            return Err(error(
                line,
                format!(
                    "{plural} for every axis or none; missing: {}",
                    absent.join(", ")
                ),
            ));
        }
        if quantity == 2 && quantities < 2 {
            return Err(error(
                line,
                "accelerations only with velocities (`<axis>:vel` columns)",
            ));
        }
        quantities = quantity + 1;
    }
    Ok((columns, quantities))
}

/// The trajectory in `text` for a group whose axes are `axes` (in its order).
pub fn parse_trajectory(text: &str, axes: &[String]) -> Result<Trajectory, CsvError> {
    let mut rows = text
        .lines()
        .enumerate()
        .map(|(index, line)| (index + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));
    let Some((header_line, header)) = rows.next() else {
        return Err(error(
            1,
            "the file is empty (expected a header `time,<axis>,…`)",
        ));
    };
    let (columns, quantities) = columns(header, header_line, axes)?;
    let mut trajectory = Trajectory::new(axes.len());
    let mut values = vec![vec![0.0; axes.len()]; 3];
    let mut points = 0;
    for (line, row) in rows {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        if fields.len() != columns.len() {
            return Err(error(
                line,
                format!(
                    "{} fields, the header has {} columns",
                    fields.len(),
                    columns.len()
                ),
            ));
        }
        let mut time = 0.0;
        for (field, column) in fields.iter().zip(&columns) {
            let value: f64 = field
                .parse()
                .map_err(|_| error(line, format!("`{field}` is not a number")))?;
            match *column {
                Column::Time => time = value,
                Column::Value(quantity, slot) => values[quantity][slot] = value,
            }
        }
        let pushed = match quantities {
            1 => trajectory.push(time, &values[0]),
            2 => trajectory.push_with_velocities(time, &values[0], &values[1]),
            _ => trajectory.push_full(time, &values[0], &values[1], &values[2]),
        };
        pushed.map_err(|problem| error(line, point_problem(&problem, axes)))?;
        points += 1;
    }
    if points == 0 {
        return Err(error(header_line, "no points after the header"));
    }
    Ok(trajectory)
}

/// A trajectory's refusal of a point in the CSV's words (axes by name).
fn point_problem(problem: &TrajectoryError, axes: &[String]) -> String {
    match problem {
        TrajectoryError::Time {
            time,
            previous: Some(previous),
            ..
        } => {
            format!("time {time} s is not after the previous row's {previous} s")
        }
        TrajectoryError::Time {
            time,
            previous: None,
            ..
        } => {
            format!("time {time} s: times start at 0 or later")
        }
        TrajectoryError::NotFinite {
            axis, what, value, ..
        } => format!(
            "{what} of `{}` is {value}, not a finite number",
            axes.get(*axis).map_or("?", String::as_str)
        ),
        TrajectoryError::TooManyPoints { max, .. } => {
            format!("more than {max} points (the most a path holds)")
        }
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gantry() -> Vec<String> {
        ["x", "feeder", "lift"]
            .iter()
            .map(|a| (*a).to_owned())
            .collect()
    }

    fn failure(text: &str) -> CsvError {
        parse_trajectory(text, &gantry()).expect_err(text)
    }

    #[test]
    fn positions_in_any_column_order() {
        let text = "# gantry pick\ntime,lift,x,feeder\n0.5, 3, 1, 2\n\n1.0,6,4,5\r\n";
        let path = parse_trajectory(text, &gantry()).unwrap();
        assert_eq!(path.times(), [0.5, 1.0]);
        assert_eq!(path.positions(0), Some(&[1.0, 2.0, 3.0][..]));
        assert_eq!(path.positions(1), Some(&[4.0, 5.0, 6.0][..]));
        assert_eq!(path.kind(), Some(motion_client::PointKind::Positions));
    }

    #[test]
    fn velocities_and_accelerations() {
        let text =
            "time,x,x:vel,feeder,feeder:vel,lift,lift:vel\n0,0,0,0,0,0,0\n1,1,0.5,2,1,3,1.5\n";
        let path = parse_trajectory(text, &gantry()).unwrap();
        assert_eq!(path.velocities(1), Some(&[0.5, 1.0, 1.5][..]));
        let text = "time,x,feeder,lift,x:vel,feeder:vel,lift:vel,x:acc,feeder:acc,lift:acc\n\
                    0.25,1,2,3,0,0,0,0,0,0\n";
        let path = parse_trajectory(text, &gantry()).unwrap();
        assert_eq!(path.kind(), Some(motion_client::PointKind::Accelerations));
        assert_eq!(path.accelerations(0), Some(&[0.0; 3][..]));
    }

    #[test]
    fn header_errors_name_line_and_column() {
        let cases = [
            ("", 1, "empty"),
            ("x,feeder,lift\n1,2,3\n", 1, "no `time` column"),
            ("time,x,feeder\n0,1,2\n", 1, "missing: lift"),
            (
                "time,x,feeder,lift,z\n",
                1,
                "`z` is not an axis of the group (its axes: x, feeder, lift)",
            ),
            ("time,x,feeder,lift,x\n", 1, "column `x` appears twice"),
            ("time,time,x,feeder,lift\n", 1, "`time` appears twice"),
            (
                "time,x,feeder,lift,x:vel\n",
                1,
                "velocities for every axis or none; missing: feeder:vel, lift:vel",
            ),
            (
                "time,x,feeder,lift,x:acc,feeder:acc,lift:acc\n",
                1,
                "accelerations only with velocities",
            ),
            ("time,x,feeder,lift,x:jerk\n", 1, "`:jerk` is neither"),
            (
                "# comment\n\ntime,x,feeder,lift\n",
                3,
                "no points after the header",
            ),
        ];
        for (text, line, words) in cases {
            let error = failure(text);
            assert_eq!(error.line, line, "{text:?}: {error}");
            assert!(error.to_string().contains(words), "{text:?}: {error}");
        }
    }

    #[test]
    fn row_errors_name_their_line() {
        let cases = [
            (
                "time,x,feeder,lift\n0,1,2\n",
                2,
                "3 fields, the header has 4 columns",
            ),
            (
                "time,x,feeder,lift\n0,1,2,3\n0.5,1,two,3\n",
                3,
                "`two` is not a number",
            ),
            (
                "time,x,feeder,lift\n1,1,2,3\n\n0.5,1,2,3\n",
                4,
                "time 0.5 s is not after the previous row's 1 s",
            ),
            (
                "time,x,feeder,lift\n-1,1,2,3\n",
                2,
                "times start at 0 or later",
            ),
            (
                "time,x,feeder,lift\n0,1,inf,3\n",
                2,
                "position of `feeder` is inf",
            ),
        ];
        for (text, line, words) in cases {
            let error = failure(text);
            assert_eq!(error.line, line, "{text:?}: {error}");
            assert!(error.to_string().contains(words), "{text:?}: {error}");
        }
    }

    #[test]
    fn at_most_the_points_a_path_holds() {
        let mut text = "time,x,feeder,lift\n".to_owned();
        for point in 0..=motion_client::ipc::MAX_PATH_POINTS {
            text.push_str(&format!("{},0,0,0\n", point + 1));
        }
        let error = failure(&text);
        assert_eq!(error.line, motion_client::ipc::MAX_PATH_POINTS + 2);
        assert!(error.message.contains("more than 1024 points"), "{error}");
    }
}
