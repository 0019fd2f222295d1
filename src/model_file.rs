//! Robot parameter files: a planar chain described in JSON or YAML, in the
//! flat layout of identified robots (`shared/robots/*.yml`): one number per
//! key, SI units, joint and link `j` numbered from 1.
//!
//! | key | meaning | default |
//! |---|---|---|
//! | `m<j>` | link mass (kg) | required |
//! | `l<j>` | link length, joint to joint (m) | required |
//! | `r<j>` | joint-to-centre-of-mass distance (m) | `l<j>` (point mass at the tip) |
//! | `I<j>` | link inertia **about its joint axis** (kg m^2), contains `m r^2` (identified base parameters may be below `m r^2`; accepted while the inertia matrix stays positive definite) | `m<j> r<j>^2` |
//! | `Ir<j>`, or `Ir` for every joint | motor rotor inertia before the gearbox (kg m^2) | 0 |
//! | `gr<j>`, or `gr` for every joint | gear ratio (motor turns per joint turn) | 1 |
//! | `b<j>` | viscous joint friction (N m s/rad) | 0 |
//! | `cf<j>` | Coulomb joint friction (N m) of `cf atan(k qd)` | 0 |
//! | `k<j>` | joint spring stiffness (N m/rad) | 0 |
//! | `q_rest<j>` | spring rest angle (rad) | 0 |
//! | `tl<j>` | motor torque limit (N m) | none |
//! | `g` | gravity (m/s^2) | required |
//! | `coulomb_sharpness` | `k` of `cf atan(k qd)` (s/rad) | 100 |
//! | `name`, `kind` | text, for the reader | |
//!
//! The number of links is the highest `j` of the `m<j>` keys (1 to
//! [`MAX_LINKS`]). A missing or unknown key, a key that is not a number and a
//! non-physical value give a one-line error naming the key and the file.

use crate::mechanics::{Joint, Link, PlanarChain, PlanarChainParams};
use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Most links a parameter file may describe: the joint-count table's
/// largest ([`crate::joints::MAX_JOINTS`]).
pub const MAX_LINKS: usize = crate::joints::MAX_JOINTS;

/// A parameter file that could not be used: the file and what is wrong.
#[derive(Debug, Error, Clone, PartialEq)]
#[error("{}: {message}", path.display())]
pub struct ModelFileError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong with it (names the key).
    pub message: String,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum Entry {
    Number(f64),
    Text(String),
    // Anything else (a list, a mapping, null): refused by name.
    Other(#[allow(dead_code)] serde::de::IgnoredAny),
}

/// A robot read from a parameter file.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotFile {
    path: PathBuf,
    links: usize,
    numbers: BTreeMap<String, f64>,
    name: Option<String>,
}

const PER_LINK: [&str; 11] = [
    "m", "l", "r", "I", "Ir", "gr", "b", "cf", "k", "q_rest", "tl",
];
const GLOBAL: [&str; 4] = ["g", "coulomb_sharpness", "Ir", "gr"];

/// Joints of the robot of an optional parameter file: the file's links, and
/// 2 (the paper's double pendulum) without one (the CLI's and the sweeps'
/// convention).
pub fn joint_count(path: Option<&Path>) -> Result<usize, ModelFileError> {
    match path {
        Some(path) => Ok(RobotFile::load(path)?.links()),
        None => Ok(2),
    }
}

impl RobotFile {
    /// Reads and checks a `.json`, `.yml` or `.yaml` file.
    pub fn load(path: impl AsRef<Path>) -> Result<Self, ModelFileError> {
        let path = path.as_ref().to_path_buf();
        let fail = |message: String| ModelFileError {
            path: path.clone(),
            message,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| fail(format!("cannot read: {e}")))?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let entries: BTreeMap<String, Entry> = match ext.as_str() {
            "json" => serde_json::from_str(&text)
                .map_err(|e| fail(format!("not a flat JSON object of numbers: {e}")))?,
            "yml" | "yaml" => yaml_serde::from_str(&text)
                .map_err(|e| fail(format!("not a flat YAML mapping of numbers: {e}")))?,
            _ => {
                return Err(fail(
                    "unknown file type: expected .json, .yml or .yaml".into(),
                ));
            }
        };
        Self::from_entries(path.clone(), entries).map_err(fail)
    }

    fn from_entries(path: PathBuf, entries: BTreeMap<String, Entry>) -> Result<Self, String> {
        let mut numbers = BTreeMap::new();
        let mut name = None;
        for (key, entry) in entries {
            match (key.as_str(), entry) {
                ("name" | "kind", Entry::Text(t)) => {
                    if key == "name" {
                        name = Some(t);
                    }
                }
                (_, Entry::Number(v)) => {
                    numbers.insert(key, v);
                }
                (_, _) => return Err(format!("key '{key}' must be a number")),
            }
        }
        let links = (1..=MAX_LINKS + 1)
            .rev()
            .find(|j| numbers.contains_key(&format!("m{j}")))
            .ok_or("missing key 'm1' (link 1 mass)")?;
        if links > MAX_LINKS {
            return Err(format!(
                "key 'm{links}': at most {MAX_LINKS} links are supported"
            ));
        }
        let mut known: BTreeSet<String> = GLOBAL.iter().map(|s| s.to_string()).collect();
        for j in 1..=links {
            for k in PER_LINK {
                known.insert(format!("{k}{j}"));
            }
        }
        if let Some(unknown) = numbers.keys().find(|k| !known.contains(*k)) {
            return Err(format!(
                "unknown key '{unknown}' (a {links}-link chain has m, l, r, I, Ir, gr, b, cf, k, q_rest, tl 1..{links}, and g, Ir, gr, coulomb_sharpness)"
            ));
        }
        for j in 1..=links {
            for k in ["m", "l"] {
                if !numbers.contains_key(&format!("{k}{j}")) {
                    return Err(format!("missing key '{k}{j}'"));
                }
            }
        }
        if !numbers.contains_key("g") {
            return Err("missing key 'g' (gravity, m/s^2)".into());
        }
        for (key, value) in &numbers {
            if !value.is_finite() {
                return Err(format!("key '{key}' = {value} must be finite"));
            }
        }
        let file = Self {
            path,
            links,
            numbers,
            name,
        };
        file.check_ranges()?;
        Ok(file)
    }

    fn check_ranges(&self) -> Result<(), String> {
        for (key, &v) in &self.numbers {
            let base = key.trim_end_matches(|c: char| c.is_ascii_digit());
            let bad = match base {
                "m" | "l" | "I" | "gr" | "coulomb_sharpness" | "tl" => v <= 0.0,
                "Ir" | "b" | "cf" | "k" | "g" => v < 0.0,
                _ => false,
            };
            if bad {
                let need = if matches!(base, "m" | "l" | "I" | "gr" | "coulomb_sharpness" | "tl") {
                    "> 0"
                } else {
                    ">= 0"
                };
                return Err(format!("key '{key}' = {v} must be {need}"));
            }
        }
        Ok(())
    }

    fn number(&self, key: &str, j: usize) -> f64 {
        self.numbers[&format!("{key}{j}")]
    }

    fn optional(&self, key: &str, j: usize) -> Option<f64> {
        self.numbers.get(&format!("{key}{j}")).copied()
    }

    fn com(&self, j: usize) -> f64 {
        self.optional("r", j).unwrap_or_else(|| self.number("l", j))
    }

    /// The file it was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of links.
    pub fn links(&self) -> usize {
        self.links
    }

    /// The `name` entry, if any.
    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }

    /// All numeric entries as given.
    pub fn entries(&self) -> &BTreeMap<String, f64> {
        &self.numbers
    }

    /// The chain's parameters; an error when the file has another number of links.
    pub fn params<const N: usize>(&self) -> Result<PlanarChainParams<N>, ModelFileError> {
        if N != self.links {
            return Err(self.error(format!(
                "describes a {}-link chain, a {N}-link model was expected",
                self.links
            )));
        }
        let per_joint = |key: &str, j: usize, default: f64| {
            self.optional(key, j)
                .or_else(|| self.numbers.get(key).copied())
                .unwrap_or(default)
        };
        let params = PlanarChainParams {
            links: std::array::from_fn(|i| {
                let j = i + 1;
                let (m, l, r) = (self.number("m", j), self.number("l", j), self.com(j));
                let inertia = self.optional("I", j).unwrap_or(m * r * r);
                Link::with_inertia_about_joint(m, l, r, inertia)
            }),
            joints: std::array::from_fn(|i| {
                let j = i + 1;
                Joint {
                    rotor_inertia: per_joint("Ir", j, 0.0),
                    gear_ratio: per_joint("gr", j, 1.0),
                    viscous: self.optional("b", j).unwrap_or(0.0),
                    coulomb: self.optional("cf", j).unwrap_or(0.0),
                    stiffness: self.optional("k", j).unwrap_or(0.0),
                    rest_angle: self.optional("q_rest", j).unwrap_or(0.0),
                }
            }),
            gravity: self.numbers["g"],
            coulomb_sharpness: self
                .numbers
                .get("coulomb_sharpness")
                .copied()
                .unwrap_or(crate::mechanics::DEFAULT_COULOMB_SHARPNESS),
        };
        Ok(params)
    }

    /// The chain, with the core's checks (stable equilibrium, positive inertia).
    pub fn chain<const N: usize>(&self) -> Result<PlanarChain<N>, ModelFileError> {
        PlanarChain::new(self.params::<N>()?).map_err(|e| self.error(e.to_string()))
    }

    /// Motor torque limits `tl<j>` (N m), when every joint has one.
    pub fn torque_limits(&self) -> Option<Vec<f64>> {
        (1..=self.links).map(|j| self.optional("tl", j)).collect()
    }

    /// An error about this file.
    pub fn error(&self, message: String) -> ModelFileError {
        ModelFileError {
            path: self.path.clone(),
            message,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::MechanicalSystem;

    fn write(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("eigenmpc-model-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn point_mass_json_is_the_paper_pendulum() {
        let p = write("paper.json", r#"{"m1":1,"m2":1,"l1":1,"l2":1,"g":9.81}"#);
        let f = RobotFile::load(&p).unwrap();
        assert_eq!(f.links(), 2);
        assert_eq!(f.params::<2>().unwrap(), PlanarChainParams::<2>::default());
    }

    #[test]
    fn errors_name_the_key_and_the_file() {
        let cases = [
            ("a.json", r#"{"m1":1,"l1":1}"#, "missing key 'g'"),
            (
                "b.json",
                r#"{"m1":1,"m2":1,"l1":1,"g":9.81}"#,
                "missing key 'l2'",
            ),
            (
                "c.json",
                r#"{"m1":1,"l1":1,"g":9.81,"mass3":2}"#,
                "unknown key 'mass3'",
            ),
            (
                "d.json",
                r#"{"m1":-1,"l1":1,"g":9.81}"#,
                "key 'm1' = -1 must be > 0",
            ),
            ("e.yml", "m1: 1\nl1: 1\ng: 9.81\ncf1: -0.1\n", "key 'cf1'"),
            ("f.yml", "m1: 1\nl1: 1\ng: 9.81\nI1: 0\n", "I1"),
            (
                "g.yml",
                "m1: 1\nl1: [1]\ng: 9.81\n",
                "key 'l1' must be a number",
            ),
            ("h.txt", "m1: 1", "unknown file type"),
            (
                "i.yml",
                "m1: 1\nl1: 1\ng: .nan\n",
                "key 'g' = NaN must be finite",
            ),
            ("j.json", "{\"m1\": 1,", "not a flat JSON object"),
        ];
        for (name, text, needle) in cases {
            let p = write(name, text);
            let err = RobotFile::load(&p).unwrap_err().to_string();
            assert!(err.contains(needle), "{name}: {err}");
            assert!(err.starts_with(&p.display().to_string()), "{err}");
            assert!(!err.contains('\n'), "one line: {err}");
        }
        let one = write("one.yml", "m1: 1\nl1: 1\ng: 9.81\n");
        let err = RobotFile::load(&one).unwrap().params::<2>().unwrap_err();
        assert!(err.to_string().contains("1-link"), "{err}");
    }

    #[test]
    fn shared_robot_files_load_with_the_published_model() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/lab-double-pendulum-A0.yml");
        let f = RobotFile::load(&p).unwrap();
        let sys = f.chain::<2>().unwrap();
        let m = sys.mass_matrix(&crate::mechanics::Vector::<2>::zeros());
        // M22 = I2 + gr^2 Ir.
        let m22 = 0.02392374528789766 + 36.0 * 7.659297952841183e-05;
        assert!((m[(1, 1)] - m22).abs() < 1e-15);
        assert_eq!(f.torque_limits(), Some(vec![10.0, 10.0]));
    }
}
