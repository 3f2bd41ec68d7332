//! What every subcommand is handed: the channel map its recordings are read
//! through (`--map`, or for `limpid rerun` the map its result was made with)
//! and the error type. A value passed down, not process-wide state, so a
//! command that switches maps (rerun) says so where it does.

use std::path::Path;

use limpid_core::{Error, Recording, Result};
use limpid_io::map::ChannelMap;

/// Errors of any crate, boxed for the CLI.
pub type CliResult<T = ()> = std::result::Result<T, Box<dyn std::error::Error + Send + Sync>>;

/// How this command reads its recordings and names its settings.
#[derive(Debug)]
pub struct Context {
    map: Option<ChannelMap>,
    /// `--column NAME=CHANNEL` pairs.
    columns: Vec<(String, String)>,
    /// The command line's definition: errors name a setting by its flag.
    commands: clap::Command,
}

impl Context {
    /// Recordings read as they are; `commands` defines the flags.
    pub fn new(commands: clap::Command) -> Self {
        Context {
            map: None,
            columns: Vec::new(),
            commands,
        }
    }

    /// The same, reading recordings through the channel map at `path` (read and checked now).
    pub fn with_map(&self, path: &Path) -> Result<Self> {
        Ok(Context {
            map: Some(ChannelMap::read(path)?),
            columns: self.columns.clone(),
            commands: self.commands.clone(),
        })
    }

    /// The same, with columns named on the command line (`--column`).
    pub fn with_columns(self, columns: Vec<(String, String)>) -> Self {
        Context { columns, ..self }
    }

    /// The same, reading recordings as they are.
    pub fn without_map(&self) -> Self {
        Context::new(self.commands.clone()).with_columns(self.columns.clone())
    }

    /// A library error about a setting, the setting named by the flag that
    /// sets it in `command` (e.g. `estimate varying`): one rule for every
    /// method, since each flag's id is the field it sets.
    pub fn with_flag_names(&self, command: &str, e: Error) -> Error {
        let Error::InvalidParameter { name, message } = e else {
            return e;
        };
        let mut cmd = &self.commands;
        for word in command.split_whitespace() {
            match cmd.find_subcommand(word) {
                Some(sub) => cmd = sub,
                None => return Error::InvalidParameter { name, message },
            }
        }
        let flag = |field: &str| {
            cmd.get_arguments()
                .find(|a| a.get_id().as_str() == field)
                .and_then(|a| a.get_long())
                .map_or_else(|| field.to_string(), |long| format!("--{long}"))
        };
        // a rule about two fields names both ("inputs/outputs")
        let name = name.split('/').map(flag).collect::<Vec<_>>().join("/");
        Error::InvalidParameter { name, message }
    }

    /// The columns named on the command line (`--column`).
    pub fn columns(&self) -> &[(String, String)] {
        &self.columns
    }

    /// The channel map recordings are read through, if any.
    pub fn channel_map(&self) -> Option<&ChannelMap> {
        self.map.as_ref()
    }

    /// The file the channel map was read from, if any.
    pub fn map_path(&self) -> Option<&Path> {
        self.map.as_ref().and_then(|m| m.path.as_deref())
    }

    /// Read a recording and say on stderr what was accepted but looks wrong.
    pub fn read_recording(&self, path: impl AsRef<Path>) -> Result<Recording> {
        let rec = limpid_io::convert_with_columns(path, self.channel_map(), &self.columns)
            .map_err(with_the_fix)?
            .recording;
        warn_about(&rec);
        Ok(rec)
    }

    /// Read a file beside the main recording (an MVC recording, calibration
    /// poses) through the map, leaving out the columns it does not record.
    pub fn read_supporting_recording(&self, path: impl AsRef<Path>) -> Result<Recording> {
        let rec = limpid_io::read_supporting_recording(path, self.channel_map())?;
        warn_about(&rec);
        Ok(rec)
    }

    /// Refuse, before any work, an output that is one of the command's inputs
    /// (the channel map counted among them; issue 56).
    pub fn refuse_overwriting_inputs(
        &self,
        outputs: &[(&Path, &str)],
        inputs: &[(&Path, &str)],
    ) -> Result<()> {
        let mut all = inputs.to_vec();
        if let Some(map) = self.map_path() {
            all.push((map, "the channel map (--map)"));
        }
        limpid_core::files::refuse_overwriting_inputs(outputs, &all)
    }
}

/// A missing column's error with the fix: the flag that names it by one of
/// the file's own columns, and the command that proposes a whole map.
fn with_the_fix(e: Error) -> Error {
    match e {
        Error::MissingColumn {
            path,
            column,
            why,
            found,
        } => {
            let example = found.split(',').next().unwrap_or("...").to_string();
            let message = format!(
                "missing required column {column} ({why}); found columns: {found}; name it with --column {column}={example} (a column of the file), or save the map `limpid inspect {} --map-template` proposes and pass --map",
                path.display()
            );
            Error::Format { path, message }
        }
        e => e,
    }
}

fn warn_about(rec: &Recording) {
    for w in rec.warnings() {
        eprintln!("limpid: warning: {}: {w}", rec.path().display());
    }
}
