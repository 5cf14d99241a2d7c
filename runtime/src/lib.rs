//! The process machine: T800-style workspaces, run queues, one-word channels, ALT, timers, PAR,
//! runtime errors and deadlock detection; nodes, links and network transports.
