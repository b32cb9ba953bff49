//! `mbfmu install [--prefix DIR]`: install this `mbfmu` as one self-contained executable,
//! `DIR/bin/mbfmu`, with the FMU library embedded ([`crate::pack::bundle`]), so that
//! `mbfmu pack` works from any directory, for any user, with no environment variable.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::Args;

use super::CliError;
use crate::pack::bundle::{bundled, image};
use crate::pack::library;

/// Arguments of `mbfmu install`.
#[derive(Clone, Debug, Args)]
pub struct InstallArgs {
    /// Installation prefix: the executable goes to PREFIX/bin/mbfmu (default: $HOME/.local).
    #[arg(long, value_name = "DIR")]
    pub prefix: Option<PathBuf>,
}

/// Write PREFIX/bin/mbfmu (through a temporary file, so a running copy is not cut short).
pub fn run(args: &InstallArgs, out: &mut dyn Write) -> Result<(), CliError> {
    let prefix = match &args.prefix {
        Some(p) => p.clone(),
        None => PathBuf::from(
            std::env::var_os("HOME").ok_or_else(|| CliError::Usage("HOME is not set: give --prefix DIR".into()))?,
        )
        .join(".local"),
    };
    let exe = std::env::current_exe().map_err(|e| CliError::io("locating the running executable", e))?;
    let lib = library()?;
    let img = image(&exe).map_err(|e| CliError::io(format!("reading {}", exe.display()), e))?;
    let bin = prefix.join("bin");
    std::fs::create_dir_all(&bin).map_err(|e| CliError::io(format!("creating {}", bin.display()), e))?;
    let dest = bin.join(exe.file_name().unwrap_or("mbfmu".as_ref()));
    let tmp = bin.join(".mbfmu.install.tmp");
    write_executable(&tmp, &bundled(&img, &lib)).map_err(|e| CliError::io(format!("writing {}", tmp.display()), e))?;
    std::fs::rename(&tmp, &dest).map_err(|e| CliError::io(format!("installing {}", dest.display()), e))?;
    writeln!(
        out,
        "installed {} ({:.1} MB, FMU library embedded); put {} on PATH",
        dest.display(),
        (img.len() + lib.len()) as f64 / 1e6,
        bin.display()
    )
    .map_err(|e| CliError::io("writing to stdout", e))
}

fn write_executable(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    std::fs::write(path, bytes)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755))?;
    }
    Ok(())
}
