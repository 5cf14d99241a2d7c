//! One module per subcommand. Each defines `Args` (its flags) and `execute(Args)`.

pub mod carm;
pub mod check;
pub mod radiosity;
pub mod run;
pub mod test;
pub mod transport;
