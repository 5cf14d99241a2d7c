//! Programs and helpers shared by the network benchmarks (`benches/network.rs`) and the MPI
//! link example (`examples/mpi_links.rs`).

#![allow(dead_code)]

use occ_runtime::HostIo;

/// Host channels that read nothing and discard output.
pub fn quiet_host() -> HostIo {
    HostIo::new(
        Box::new(std::io::empty()),
        Box::new(std::io::sink()),
        Box::new(std::io::sink()),
    )
}

/// Node 0 sends `n` messages of `bytes` bytes to node 1 on link 1, which answers each with
/// the same message back.
pub fn ping_pong(n: u64, bytes: usize) -> String {
    r"PROTOCOL MSG IS [BYTES]BYTE:
PROC node (VAL INT id, nodes, []CHAN OF MSG in?, out!, CHAN BYTE keyboard?, screen!, error!)
  [BYTES]BYTE buf:
  IF
    id = 0
      SEQ i = 0 FOR COUNT
        SEQ
          out[1] ! buf
          in[1] ? buf
    TRUE
      SEQ i = 0 FOR COUNT
        SEQ
          in[0] ? buf
          out[0] ! buf
:
"
    .replace("BYTES", &bytes.to_string())
    .replace("COUNT", &n.to_string())
}
