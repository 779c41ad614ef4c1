//! Errors of fitting: bad input files, bad sections, bad measurements, bad scans.

use std::path::{Path, PathBuf};

/// Everything that stops a fit, with the file, line or key, and section it concerns.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The input file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A JSON sections file is malformed.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Json {
        path: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    /// A TOML measurements file is malformed.
    #[error("{}: {message}", path.display())]
    Toml { path: PathBuf, message: String },
    /// A CSV sections file is malformed.
    #[error("{}:{line}: {message}", path.display())]
    Csv {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// A value outside what it may be.
    #[error("{}: key '{key}': {message}", path.display())]
    Key {
        path: PathBuf,
        key: String,
        message: String,
    },
    /// Several values outside what they may be: (key, message) each.
    #[error("{}: {}", path.display(), crate::scene::key_problems(problems))]
    Keys {
        path: PathBuf,
        problems: Vec<(String, String)>,
    },
    /// Too few sections for a surface.
    #[error("{found} section(s): a surface needs at least 3 at different heights")]
    TooFewSections { found: usize },
    /// More sections than a fit takes: its time grows as their square (5,000 took 36 s,
    /// 100,000 would take hours).
    #[error("{found} sections: at most {limit} (a fit's time grows as the square of their number); give fewer")]
    TooManySections { found: usize, limit: usize },
    /// A section with too few distinct points.
    #[error("section {section} (height {h}): {found} distinct point(s); a section needs at least 3", h = crate::math::short(*height))]
    TooFewPoints {
        section: usize,
        height: f64,
        found: usize,
    },
    /// A section with no area.
    #[error("section {section} (height {h}) is degenerate: its points are collinear (area {area:.3e})", h = crate::math::short(*height))]
    Degenerate {
        section: usize,
        height: f64,
        area: f64,
    },
    /// Two different sections at one height.
    #[error("sections {first} and {second} are both at height {h} but differ: give one section per height", h = crate::math::short(*height))]
    DuplicateHeight {
        first: usize,
        second: usize,
        height: f64,
    },
    /// NaN or infinity in a section.
    #[error("section {section}: {what} is not a finite number")]
    NonFinite { section: usize, what: String },
    /// The scan has no torso loop at a level.
    #[error("scan level {level} (height {height:.4}): {reason}")]
    Scan {
        level: usize,
        height: f64,
        reason: String,
    },
    /// A body mesh is clearly longer along another axis than along the up axis it was given
    /// (`--up`, default z): a standing body is tallest along its up axis.
    #[error("{}: the body is {e} long along {longest} but only {h} along the up axis {given} (--up {given}): a standing body is tallest along its up axis; {advice}", path.display(), e = crate::math::short(*extent), h = crate::math::short(*height), advice = up_advice(*longest, *other))]
    UpAxis {
        path: PathBuf,
        given: crate::mesh::transform::Up,
        height: f64,
        longest: char,
        extent: f64,
        /// The other up axis drapekit reads (y or z) when the body is clearly taller along it
        /// than along `given` (a T-posed body is widest along x, its arm span, and tall along
        /// this one).
        other: Option<char>,
    },
    /// A mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] crate::io::IoError),
    /// A count from a flag or a file above what the fit may allocate.
    #[error("{flag} {value}: at most {limit} {what}")]
    TooLarge {
        flag: String,
        value: u64,
        limit: u64,
        what: String,
    },
    /// A count from a flag below what the fit needs.
    #[error("{flag} {value}: at least {min} {what}")]
    TooSmall {
        flag: String,
        value: u64,
        min: u64,
        what: String,
    },
    /// Several problems, each its own error.
    #[error("{} problems:{}", .0.len(), .0.iter().map(|e| format!("\n  {e}")).collect::<String>())]
    Several(Vec<FitError>),
    /// Options that cannot work together.
    #[error("{0}")]
    Options(String),
    /// A problem of the sections read from (or made from) the input file `path`: a sections
    /// file, a measurement set, a body mesh ([`FitError::in_file`]).
    #[error("{}: {error}", path.display())]
    InFile { path: PathBuf, error: Box<FitError> },
}

impl FitError {
    /// `Ok` for no problems, [`FitError::Key`] for one, [`FitError::Keys`] for more.
    pub fn from_keys(path: &Path, mut problems: Vec<(String, String)>) -> Result<(), FitError> {
        let path = path.to_path_buf();
        match problems.len() {
            0 => Ok(()),
            1 => {
                let (key, message) = problems.remove(0);
                Err(FitError::Key { path, key, message })
            }
            _ => Err(FitError::Keys { path, problems }),
        }
    }

    /// `Ok` for no problems, the problem for one, [`FitError::Several`] for more.
    pub fn from_problems(mut problems: Vec<FitError>) -> Result<(), FitError> {
        match problems.len() {
            0 => Ok(()),
            1 => Err(problems.remove(0)),
            _ => Err(FitError::Several(problems)),
        }
    }

    /// This error with the input file it concerns, when it does not name one already (the
    /// problems of sections and scan levels).
    pub fn in_file(self, path: &Path) -> FitError {
        match self {
            FitError::TooFewSections { .. }
            | FitError::TooManySections { .. }
            | FitError::TooFewPoints { .. }
            | FitError::Degenerate { .. }
            | FitError::DuplicateHeight { .. }
            | FitError::NonFinite { .. }
            | FitError::Scan { .. } => FitError::InFile {
                path: path.to_path_buf(),
                error: Box::new(self),
            },
            e => e,
        }
    }
}

/// What to do when a body is tallest along `axis` (x, y or z) and another up axis was given.
fn up_advice(axis: char, other: Option<char>) -> String {
    match (axis, other) {
        ('y' | 'z', _) => format!("give --up {axis}"),
        (_, Some(o)) => format!("give --up {o} (arms out, a body can be wider than tall)"),
        _ => "drapekit reads y-up and z-up bodies: rotate it to stand along y or z".into(),
    }
}
