//! A network run spread over several processes: what each rank sends rank 0 at the end (its
//! nodes' outcomes and its links' statistics), and how rank 0 puts the whole run together.
//!
//! A link between ranks has a half in each (see `occ_runtime::remote`): the reader's half counts
//! messages, bytes and the reader's blocked time, the writer's half the writer's blocked time.

use std::time::Duration;

use occ_runtime::{ErrorKind, Halt, LinkStats, RunError, Stats};

use crate::network::NodeOutcome;

/// Which part of a link a rank holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LinkPart {
    /// Both ends (an in-process link).
    Whole = 0,
    /// The writer's half of a link between ranks.
    Writer = 1,
    /// The reader's half.
    Reader = 2,
}

/// Encodes one rank's part of a run: `(node number, outcome)` and `(link number, part, stats)`.
pub(crate) fn encode(
    nodes: &[(usize, NodeOutcome)],
    links: &[(usize, LinkPart, LinkStats)],
) -> Vec<u8> {
    let mut b = Vec::new();
    put(&mut b, nodes.len() as u64);
    for (i, n) in nodes {
        put(&mut b, *i as u64);
        put_str(&mut b, &n.name);
        match &n.result {
            Ok(()) => put(&mut b, 0),
            Err(RunError::Halted(h)) if h.kind == Some(ErrorKind::Stopped) => put(&mut b, 1),
            Err(e) => {
                put(&mut b, 2);
                put_str(&mut b, &e.to_string());
            }
        }
        let s = &n.stats;
        for v in [
            s.processes_started,
            s.context_switches,
            s.communications,
            s.peak_workspace_bytes,
            n.busy.as_nanos() as u64,
        ] {
            put(&mut b, v);
        }
    }
    put(&mut b, links.len() as u64);
    for (id, part, l) in links {
        put(&mut b, *id as u64);
        put(&mut b, *part as u64);
        put_str(&mut b, &l.name);
        for v in [
            l.messages,
            l.bytes,
            l.writer_blocked.as_nanos() as u64,
            l.reader_blocked.as_nanos() as u64,
        ] {
            put(&mut b, v);
        }
    }
    b
}

/// Puts the parts of every rank together: the nodes and links in plan order.
pub(crate) fn merge(blobs: &[Vec<u8>]) -> (Vec<NodeOutcome>, Vec<LinkStats>) {
    let mut nodes = Vec::new();
    let mut links: Vec<(usize, LinkStats)> = Vec::new();
    for blob in blobs {
        let mut r = Reader { b: blob, at: 0 };
        for _ in 0..r.u64() {
            let i = r.u64() as usize;
            let name = r.string();
            let result = match r.u64() {
                0 => Ok(()),
                1 => Err(RunError::Halted(Halt {
                    kind: Some(ErrorKind::Stopped),
                    code: ErrorKind::Stopped as i64,
                    location: None,
                    proc_name: None,
                    detail: None,
                })),
                _ => Err(RunError::Remote(r.string())),
            };
            let stats = Stats {
                processes_started: r.u64(),
                context_switches: r.u64(),
                communications: r.u64(),
                peak_workspace_bytes: r.u64(),
            };
            let busy = Duration::from_nanos(r.u64());
            nodes.push((
                i,
                NodeOutcome {
                    name,
                    result,
                    stats,
                    busy,
                },
            ));
        }
        for _ in 0..r.u64() {
            let id = r.u64() as usize;
            let part = r.u64();
            let name = r.string();
            let (messages, bytes) = (r.u64(), r.u64());
            let writer_blocked = Duration::from_nanos(r.u64());
            let reader_blocked = Duration::from_nanos(r.u64());
            let l = match links.iter().position(|(j, _)| *j == id) {
                Some(k) => &mut links[k].1,
                None => {
                    links.push((
                        id,
                        LinkStats {
                            name,
                            ..LinkStats::default()
                        },
                    ));
                    &mut links.last_mut().expect("just pushed").1
                }
            };
            if part != LinkPart::Writer as u64 {
                l.messages += messages;
                l.bytes += bytes;
                l.reader_blocked += reader_blocked;
            }
            if part != LinkPart::Reader as u64 {
                l.writer_blocked += writer_blocked;
            }
        }
    }
    nodes.sort_by_key(|n| n.0);
    links.sort_by_key(|l| l.0);
    (
        nodes.into_iter().map(|n| n.1).collect(),
        links.into_iter().map(|l| l.1).collect(),
    )
}

fn put(b: &mut Vec<u8>, v: u64) {
    b.extend_from_slice(&v.to_le_bytes());
}

fn put_str(b: &mut Vec<u8>, s: &str) {
    put(b, s.len() as u64);
    b.extend_from_slice(s.as_bytes());
}

/// Reads what `encode` wrote (a rank of the same binary wrote it; short input reads as zeros).
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn u64(&mut self) -> u64 {
        const N: usize = std::mem::size_of::<u64>();
        let v = self
            .b
            .get(self.at..self.at + N)
            .map_or(0, |s| u64::from_le_bytes(s.try_into().unwrap_or([0; N])));
        self.at += N;
        v
    }

    fn string(&mut self) -> String {
        let n = self.u64() as usize;
        let end = (self.at + n).min(self.b.len());
        let s = String::from_utf8_lossy(self.b.get(self.at..end).unwrap_or(&[])).into_owned();
        self.at = end;
        s
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn parts_of_a_run_merge_in_plan_order() {
        let node = |name: &str, result| NodeOutcome {
            name: name.into(),
            result,
            stats: Stats {
                communications: 3,
                ..Stats::default()
            },
            busy: Duration::from_millis(2),
        };
        let link = |m, w, r| LinkStats {
            name: "c".into(),
            messages: m,
            bytes: 8 * m,
            writer_blocked: Duration::from_nanos(w),
            reader_blocked: Duration::from_nanos(r),
        };
        let a = encode(
            &[(1, node("node 1", Err(RunError::Remote("boom".into()))))],
            &[(0, LinkPart::Writer, link(0, 5, 7))],
        );
        let b = encode(
            &[(0, node("node 0", Ok(())))],
            &[
                (0, LinkPart::Reader, link(4, 9, 11)),
                (1, LinkPart::Whole, link(2, 1, 1)),
            ],
        );
        let (nodes, links) = merge(&[a, b]);
        assert_eq!(nodes[0].name, "node 0");
        assert!(nodes[0].result.is_ok());
        assert_eq!(nodes[1].result.as_ref().unwrap_err().to_string(), "boom");
        assert_eq!(nodes[1].stats.communications, 3);
        assert_eq!(links[0], link(4, 5, 11));
        assert_eq!(links[1], link(2, 1, 1));
    }
}
