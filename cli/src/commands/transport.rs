//! `occ run --transport`: where the nodes of a network run.
//!
//! - `inproc` (the default): every node on the thread pool of this process.
//! - `mpi` (a build with `--features mpi`, started by `mpirun -np K`): every rank compiles the
//!   program and builds the same network plan; node `i` of `n` runs on rank `i * K / n`
//!   (balanced blocks in node order, see `occ_runtime::remote::Spread`), links between ranks
//!   are MPI messages with occam's synchronous semantics, and rank 0, which holds the host's
//!   channels, prints the output, the errors and `--stats`. Without `mpirun` it runs as one rank.

use occ_runtime::remote::Transport;

/// The `--transport` choices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Kind {
    /// Every node in this process.
    #[default]
    Inproc,
    /// Nodes spread over the ranks of `mpirun` (needs a build with `--features mpi`).
    Mpi,
}

/// The transport of a run: none for `inproc`.
pub struct Chosen {
    #[cfg(feature = "mpi")]
    mpi: Option<occ_runtime::mpi::Mpi>,
}

impl Chosen {
    /// Sets up `kind` (initialising MPI for `mpi`).
    pub fn new(kind: Kind) -> anyhow::Result<Chosen> {
        match kind {
            Kind::Inproc => Ok(Chosen {
                #[cfg(feature = "mpi")]
                mpi: None,
            }),
            #[cfg(feature = "mpi")]
            Kind::Mpi => Ok(Chosen {
                mpi: Some(occ_runtime::mpi::Mpi::init().map_err(anyhow::Error::msg)?),
            }),
            #[cfg(not(feature = "mpi"))]
            Kind::Mpi => anyhow::bail!(
                "this occ was built without MPI: build it with `cargo build --features mpi` (needs OpenMPI and libclang) and start it with `mpirun -np K occ run ... --transport mpi`"
            ),
        }
    }

    /// The transport to spread a network over, if any.
    pub fn transport(&mut self) -> Option<&mut dyn Transport> {
        #[cfg(feature = "mpi")]
        if let Some(m) = self.mpi.as_mut() {
            return Some(m);
        }
        None
    }

    /// Whether this process reports (prints diagnostics, errors and statistics): rank 0, or the
    /// only process.
    pub fn reports(&mut self) -> bool {
        self.transport().is_none_or(|t| t.spread().rank == 0)
    }
}
