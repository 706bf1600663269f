//! Which keys a config file set, so that effective parameters can be shown as "from the
//! config" or "default" (`motionctl list`).

use std::collections::BTreeSet;

/// What a key belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Owner {
    /// `[server]`.
    Server,
    /// `[[link]]` n.
    Link(usize),
    /// `[[device]]` n.
    Device(usize),
    /// `[[axis]]` n.
    Axis(usize),
    /// `[[signal]]` n.
    Signal(usize),
    /// `[[group]]` n.
    Group(usize),
}

/// The dotted key paths a file set, per owner (`home.direction` for `home = { direction =
/// … }` of an axis).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct GivenKeys {
    keys: BTreeSet<(Owner, String)>,
}

impl GivenKeys {
    /// The keys of `source` (a file that already parsed as TOML).
    pub fn of(source: &str) -> Self {
        let mut given = Self::default();
        let Ok(table) = source.parse::<toml::Table>() else {
            return given;
        };
        for (section, value) in &table {
            match (section.as_str(), value) {
                ("server", toml::Value::Table(t)) => given.walk(Owner::Server, "", t),
                (kind, toml::Value::Array(items)) => {
                    for (index, item) in items.iter().enumerate() {
                        let owner = match kind {
                            "link" => Owner::Link(index),
                            "device" => Owner::Device(index),
                            "axis" => Owner::Axis(index),
                            "signal" => Owner::Signal(index),
                            "group" => Owner::Group(index),
                            _ => continue,
                        };
                        if let toml::Value::Table(t) = item {
                            given.walk(owner, "", t);
                        }
                    }
                }
                _ => {}
            }
        }
        given
    }

    fn walk(&mut self, owner: Owner, prefix: &str, table: &toml::Table) {
        for (key, value) in table {
            let path = if prefix.is_empty() {
                key.clone()
            } else {
                format!("{prefix}.{key}")
            };
            if let toml::Value::Table(inner) = value {
                self.walk(owner, &path, inner);
            }
            self.keys.insert((owner, path));
        }
    }

    /// Whether the file set `key` (a dotted path; a table counts when any key in it was
    /// set) on `owner`.
    pub fn contains(&self, owner: Owner, key: &str) -> bool {
        self.keys.contains(&(owner, key.to_owned()))
    }

    /// Records `key` on `owner` as set (tests, and keys set through an alias).
    pub fn insert(&mut self, owner: Owner, key: &str) {
        self.keys.insert((owner, key.to_owned()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_keys_are_dotted_per_owner() {
        let given = GivenKeys::of(
            "[server]\nname = \"x\"\n[[axis]]\nname = \"a\"\n[[axis]]\nhome = { direction = \"positive\" }\n",
        );
        assert!(given.contains(Owner::Server, "name"));
        assert!(given.contains(Owner::Axis(0), "name"));
        assert!(!given.contains(Owner::Axis(1), "name"));
        assert!(given.contains(Owner::Axis(1), "home"));
        assert!(given.contains(Owner::Axis(1), "home.direction"));
        assert!(!given.contains(Owner::Axis(1), "home.max_travel"));
    }

    #[test]
    fn group_keys_belong_to_their_group() {
        let given =
            GivenKeys::of("[[group]]\nname = \"g\"\n[[group]]\npath_tolerance = { x = 1.0 }\n");
        assert!(given.contains(Owner::Group(0), "name"));
        assert!(given.contains(Owner::Group(1), "path_tolerance.x"));
        assert!(!given.contains(Owner::Group(1), "goal_tolerance"));
    }
}
