//! Networks: the program's configuration as occam 2 wrote it, a top-level `PLACED PAR` of
//! `PROCESSOR n` processes.
//!
//! The last top-level PROC (the one `occ run` starts) may end in a `PLACED PAR`, plain or
//! replicated, possibly nested, whose leaves are `PROCESSOR n` processes. Each PROCESSOR instance
//! (one per value of the enclosing replicators) becomes a node. The declarations before the
//! PLACED PAR are configuration: every node has its own copy. A channel declared there and used
//! on two processors becomes a link (the one that outputs is its writer, the one that inputs its
//! reader); one used on a single processor stays a soft channel of that node.
//!
//! [`configure`] finds which channel each processor uses by walking its body with the replicator
//! indices bound to their values for that instance: subscripts are evaluated, IF and CASE take
//! the branch their constant condition selects, and channels passed to a PROC take the direction
//! of its parameter (its specifier, or the PROC's usage summary). It reports, at the offending
//! line: a processor number used twice; a replicator whose base or count is not constant; a
//! channel used on three processors, or for input (or output) on both of its two; a processor
//! that needs more than four links; the host's channels (the PROC's parameters) used anywhere
//! but on the root, the lowest-numbered processor; a link subscript it cannot evaluate; and a
//! `PLACED PAR` or `PROCESSOR` anywhere else.

use std::collections::BTreeMap;

use occ_grammar::ast::{
    self, AltKind, BinOp, ChoiceKind, DeclKind, Expr, ExprKind, Process, ProcessKind, Span, UnOp,
};

use crate::checked::{CheckedProgram, FxHashMap, SymbolId, SymbolKind};
use crate::diagnostic::{Diagnostic, DiagnosticKind};
use crate::types::{Direction, Type};
use crate::usage::Mode;

/// The most processor instances a configuration may have.
pub const MAX_PROCESSORS: usize = 4096;
/// Links a transputer has.
pub const LINKS_PER_PROCESSOR: usize = 4;
/// The most iterations a replicator inside a processor body is unrolled for the analysis.
const MAX_UNROLL: i64 = 4096;

/// A program's network: its processors and the links between them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Network {
    /// The outermost `PLACED PAR`.
    pub span: Span,
    /// The `PROCESSOR` processes of the text, in textual order.
    pub branches: Vec<Branch>,
    /// Every processor instance, in increasing order of number: node `i` runs `processors[i]`,
    /// and node 0 is the root, which holds the host's channels.
    pub processors: Vec<Placement>,
    /// Every channel (element) used on two processors.
    pub links: Vec<Link>,
}

/// One `PROCESSOR` process of the text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Branch {
    /// The `PROCESSOR` process.
    pub span: Span,
    /// The replicator indices of the enclosing `PLACED PAR`s, outermost first.
    pub replicators: Vec<SymbolId>,
}

/// One processor instance.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Placement {
    /// Its number, as written after `PROCESSOR`.
    pub number: i64,
    /// The index of its `PROCESSOR` process in [`Network::branches`].
    pub branch: usize,
    /// The values of that branch's replicators for this instance.
    pub values: Vec<i64>,
}

/// A channel (or channel array element) that joins two processors.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Link {
    /// The channel (or channel array) declared before the `PLACED PAR`.
    pub channel: SymbolId,
    /// The element's index in the array, flattened row-major (0 for a single channel).
    pub element: u32,
    /// A readable name: `c` or `ring[3]`.
    pub name: String,
    /// The index in [`Network::processors`] of the processor that outputs on it.
    pub writer: usize,
    /// The index of the processor that inputs from it.
    pub reader: usize,
}

/// Finds the network of `program` (checked as `checked`): `None` when its last PROC is not a
/// `PLACED PAR`. Never panics; every problem is a diagnostic.
pub fn configure(
    program: &ast::Program,
    checked: &CheckedProgram,
) -> (Option<Network>, Vec<Diagnostic>) {
    let mut cx = Config {
        checked,
        diags: Vec::new(),
    };
    let entry = program.decls.iter().rev().find_map(|d| match &d.kind {
        DeclKind::Proc { params, body, .. } => Some((params, body)),
        _ => None,
    });
    let mut top = None;
    if let Some((params, body)) = entry {
        let (decls, inner) = peel(body);
        if matches!(inner.kind, ProcessKind::Par { placed: true, .. }) {
            top = Some((params, decls, inner));
        }
    }
    // A PLACED PAR or PROCESSOR anywhere but at the top of the last PROC.
    let top_span = top.as_ref().map(|t| t.2.span);
    for d in &program.decls {
        cx.stray_decl(d, top_span);
    }
    let Some((params, decls, placed)) = top else {
        return (None, cx.diags);
    };
    let network = cx.network(params, &decls, placed);
    (network, cx.diags)
}

/// The declarations wrapping a process, and the process inside them.
fn peel(p: &Process) -> (Vec<&ast::Decl>, &Process) {
    let mut decls = Vec::new();
    let mut p = p;
    while let ProcessKind::Scope { decls: ds, body } = &p.kind {
        decls.extend(ds);
        p = body;
    }
    (decls, p)
}

struct Config<'a> {
    checked: &'a CheckedProgram,
    diags: Vec<Diagnostic>,
}

/// Values of replicator indices known for the instance being walked.
type Env = FxHashMap<SymbolId, i64>;

/// A set of channel elements: the configuration channel and the flattened element indices.
#[derive(Clone, Debug)]
struct Target {
    channel: SymbolId,
    elements: Vec<u32>,
}

/// One use of a channel element: by which processor instance, which way, where.
#[derive(Clone, Copy, Debug)]
struct Use {
    processor: usize,
    mode: Mode,
    span: Span,
}

fn error(what: String, help: &'static str, span: Span) -> Diagnostic {
    Diagnostic::error(DiagnosticKind::Network { what, help }, span)
}

impl<'a> Config<'a> {
    fn symbol(&self, name: &ast::Name) -> Option<SymbolId> {
        self.checked.names.get(&name.span).copied()
    }

    fn stray_decl(&mut self, d: &ast::Decl, top: Option<Span>) {
        match &d.kind {
            DeclKind::Proc { body, .. } => self.stray(body, top),
            DeclKind::Function {
                body: ast::FunctionBody::Valof(v),
                ..
            } => self.stray(&v.body, top),
            _ => {}
        }
    }

    /// Reports every PLACED PAR or PROCESSOR in `p` except the one at `top` (whose own
    /// PROCESSORs the network walk checks).
    fn stray(&mut self, p: &Process, top: Option<Span>) {
        if Some(p.span) == top {
            return;
        }
        match &p.kind {
            ProcessKind::Par { placed: true, .. } => {
                // One error for the whole misplaced configuration, not one per PROCESSOR.
                self.diags.push(error(
                    "PLACED PAR must be the outermost process of the program's last PROC".into(),
                    "a network is configured once, at the top: PROC main (...) / declarations / PLACED PAR",
                    p.span,
                ));
                return;
            }
            ProcessKind::Processor { .. } => self.diags.push(error(
                "PROCESSOR may only appear directly inside a PLACED PAR".into(),
                "write PLACED PAR, then one PROCESSOR n per transputer",
                p.span,
            )),
            _ => {}
        }
        let (decls, procs) = children(p);
        decls.into_iter().for_each(|d| self.stray_decl(d, top));
        procs.into_iter().for_each(|q| self.stray(q, top));
    }

    fn network(
        &mut self,
        params: &[ast::Param],
        decls: &[&ast::Decl],
        placed: &Process,
    ) -> Option<Network> {
        let before = self.diags.len();
        let mut branches = Vec::new();
        let mut found = Vec::new();
        let mut env = Env::default();
        self.instances(placed, &mut env, &mut Vec::new(), &mut branches, &mut found);
        if self.diags.len() > before {
            return None;
        }
        // Order by number; a number used twice is an error.
        found.sort_by_key(|(p, _): &(Placement, Span)| p.number);
        for w in found.windows(2) {
            if w[0].0.number == w[1].0.number {
                self.diags.push(
                    error(
                        format!("PROCESSOR {} is placed twice", w[1].0.number),
                        "give every processor instance its own number",
                        w[1].1,
                    )
                    .with_related(w[0].1, "first placed here"),
                );
            }
        }
        if self.diags.len() > before {
            return None;
        }
        let processors: Vec<Placement> = found.into_iter().map(|(p, _)| p).collect();
        let channels = self.config_channels(decls);
        let host: Vec<SymbolId> = params.iter().filter_map(|p| self.symbol(&p.name)).collect();
        let mut uses: BTreeMap<(SymbolId, u32), Vec<Use>> = BTreeMap::new();
        for (i, pl) in processors.iter().enumerate() {
            let b: &Branch = &branches[pl.branch];
            let mut env: Env = b
                .replicators
                .iter()
                .copied()
                .zip(pl.values.iter().copied())
                .collect();
            let body = processor_body(placed, b.span);
            let mut walk = Walk {
                cx: self,
                channels: &channels,
                host: &host,
                processor: i,
                aliases: FxHashMap::default(),
                uses: &mut uses,
            };
            if let Some(body) = body {
                walk.process(body, &mut env);
            }
        }
        if self.diags.len() > before {
            return None;
        }
        let links = self.links(&processors, &uses);
        (self.diags.len() == before).then_some(Network {
            span: placed.span,
            branches,
            processors,
            links,
        })
    }

    /// Enumerates the processor instances under `p` (a PLACED PAR or a PROCESSOR).
    fn instances(
        &mut self,
        p: &Process,
        env: &mut Env,
        reps: &mut Vec<SymbolId>,
        branches: &mut Vec<Branch>,
        found: &mut Vec<(Placement, Span)>,
    ) {
        match &p.kind {
            ProcessKind::Par {
                placed: true,
                repl,
                body,
                ..
            } => {
                let Some(r) = repl else {
                    for q in body {
                        self.instances(q, env, reps, branches, found);
                    }
                    return;
                };
                let (Some(base), Some(count)) = (self.eval(&r.base, env), self.eval(&r.count, env))
                else {
                    self.diags.push(error(
                        "the replicator of a PLACED PAR must have a constant base and count".into(),
                        "a network's size is fixed when it is configured: use VAL constants",
                        r.span,
                    ));
                    return;
                };
                let step = r.step.as_ref().map_or(Some(1), |s| self.eval(s, env));
                let Some(step) = step else {
                    self.diags.push(error(
                        "the STEP of a PLACED PAR replicator must be constant".into(),
                        "a network's size is fixed when it is configured: use VAL constants",
                        r.span,
                    ));
                    return;
                };
                if count < 0 || count as usize + found.len() > MAX_PROCESSORS {
                    self.diags.push(error(
                        format!(
                            "a PLACED PAR of {count} processors is outside 0..{MAX_PROCESSORS}"
                        ),
                        "configure fewer processors",
                        r.span,
                    ));
                    return;
                }
                let Some(sym) = self.symbol(&r.name) else {
                    return;
                };
                reps.push(sym);
                for k in 0..count {
                    env.insert(sym, base + k * step);
                    for q in body {
                        self.instances(q, env, reps, branches, found);
                    }
                }
                env.remove(&sym);
                reps.pop();
            }
            ProcessKind::Processor { number, .. } => {
                let Some(n) = self.eval(number, env) else {
                    self.diags.push(error(
                        "a PROCESSOR number must be a constant (or computed from PLACED PAR replicators)"
                            .into(),
                        "write PROCESSOR 3, or PROCESSOR i for a replicated PLACED PAR",
                        number.span,
                    ));
                    return;
                };
                let branch = match branches.iter().position(|b| b.span == p.span) {
                    Some(b) => b,
                    None => {
                        branches.push(Branch {
                            span: p.span,
                            replicators: reps.clone(),
                        });
                        branches.len() - 1
                    }
                };
                let values = reps
                    .iter()
                    .map(|s| env.get(s).copied().unwrap_or(0))
                    .collect();
                found.push((
                    Placement {
                        number: n,
                        branch,
                        values,
                    },
                    p.span,
                ));
            }
            _ => self.diags.push(error(
                "a PLACED PAR holds only PROCESSOR processes (or nested PLACED PARs)".into(),
                "put this process inside a PROCESSOR",
                p.span,
            )),
        }
    }

    /// The channels declared before the PLACED PAR.
    fn config_channels(&self, decls: &[&ast::Decl]) -> FxHashMap<SymbolId, Vec<u32>> {
        let mut out = FxHashMap::default();
        for d in decls {
            if let DeclKind::Var { names, .. } = &d.kind {
                for n in names {
                    let Some(sym) = self.symbol(n) else { continue };
                    let s = &self.checked.symbols[sym];
                    if let Some(dims) = chan_dims(&s.ty) {
                        out.insert(sym, dims);
                    }
                }
            }
        }
        out
    }

    /// Joins the two users of each shared element into a link; reports misuse.
    fn links(
        &mut self,
        processors: &[Placement],
        uses: &BTreeMap<(SymbolId, u32), Vec<Use>>,
    ) -> Vec<Link> {
        let mut links = Vec::new();
        for (&(channel, element), us) in uses {
            let mut on: Vec<usize> = us.iter().map(|u| u.processor).collect();
            on.sort_unstable();
            on.dedup();
            if on.len() < 2 {
                continue;
            }
            let name = self.element_name(channel, element);
            let numbers = |ps: &[usize]| {
                ps.iter()
                    .map(|&p| processors[p].number.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            if on.len() > 2 {
                let third = us
                    .iter()
                    .find(|u| u.processor == on[2])
                    .map_or(us[0].span, |u| u.span);
                self.diags.push(error(
                    format!(
                        "channel `{name}` is used on {} processors (PROCESSOR {}): a link joins two",
                        on.len(),
                        numbers(&on)
                    ),
                    "give each pair of processors a channel of its own",
                    third,
                ));
                continue;
            }
            let modes = |p: usize| {
                let m: Vec<Mode> = us
                    .iter()
                    .filter(|u| u.processor == p)
                    .map(|u| u.mode)
                    .collect();
                (m.contains(&Mode::Output), m.contains(&Mode::Input))
            };
            let (a, b) = (on[0], on[1]);
            let (a_out, a_in) = modes(a);
            let (b_out, b_in) = modes(b);
            let (writer, reader) = match (a_out, a_in, b_out, b_in) {
                (true, false, false, true) => (a, b),
                (false, true, true, false) => (b, a),
                _ => {
                    let way = if a_in && b_in { "input" } else { "output" };
                    let span = us
                        .iter()
                        .rev()
                        .find(|u| u.processor == b)
                        .map_or(us[0].span, |u| u.span);
                    self.diags.push(error(
                        format!(
                            "channel `{name}` joins PROCESSOR {} and PROCESSOR {}, but both use it for {way}",
                            processors[a].number, processors[b].number
                        ),
                        "a link carries a channel one way: one processor outputs, the other inputs",
                        span,
                    ));
                    continue;
                }
            };
            links.push(Link {
                channel,
                element,
                name,
                writer,
                reader,
            });
        }
        self.count_links(processors, &links, uses);
        links
    }

    /// Reports processors that need more than four links: each neighbour needs as many links as
    /// there are channels to it in the busier direction.
    fn count_links(
        &mut self,
        processors: &[Placement],
        links: &[Link],
        uses: &BTreeMap<(SymbolId, u32), Vec<Use>>,
    ) {
        for p in 0..processors.len() {
            let mut per: BTreeMap<usize, (usize, usize)> = BTreeMap::new();
            for l in links {
                if l.writer == p {
                    per.entry(l.reader).or_default().0 += 1;
                } else if l.reader == p {
                    per.entry(l.writer).or_default().1 += 1;
                }
            }
            let needed: usize = per.values().map(|&(o, i)| o.max(i)).sum();
            if needed > LINKS_PER_PROCESSOR {
                let span = links
                    .iter()
                    .rev()
                    .filter(|l| l.writer == p || l.reader == p)
                    .find_map(|l| {
                        uses.get(&(l.channel, l.element))?
                            .iter()
                            .find(|u| u.processor == p)
                            .map(|u| u.span)
                    })
                    .unwrap_or_default();
                let to: Vec<String> = per
                    .keys()
                    .map(|&q| processors[q].number.to_string())
                    .collect();
                self.diags.push(error(
                    format!(
                        "PROCESSOR {} needs {needed} links (to PROCESSOR {}), but a transputer has {LINKS_PER_PROCESSOR}",
                        processors[p].number,
                        to.join(", ")
                    ),
                    "route some traffic through a neighbour, or choose a topology of degree four or less",
                    span,
                ));
            }
        }
    }

    fn element_name(&self, channel: SymbolId, element: u32) -> String {
        let s = &self.checked.symbols[channel];
        let dims = chan_dims(&s.ty).unwrap_or_default();
        if dims.is_empty() {
            return s.name.clone();
        }
        let mut rest = element;
        let mut idx = Vec::new();
        for (k, _) in dims.iter().enumerate() {
            let inner: u32 = dims[k + 1..].iter().product();
            idx.push(rest / inner.max(1));
            rest %= inner.max(1);
        }
        let subs: String = idx.iter().map(|i| format!("[{i}]")).collect();
        format!("{}{subs}", s.name)
    }

    /// The integer (or boolean, as 0/1) value of `e` with replicators bound by `env`.
    fn eval(&self, e: &Expr, env: &Env) -> Option<i64> {
        if let Some(v) = self.checked.constants.get(&e.span) {
            return v.as_int().or_else(|| v.as_bool().map(i64::from));
        }
        if self.checked.operators.contains_key(&e.span) {
            return None;
        }
        match &e.kind {
            ExprKind::Name(n) => env.get(&self.symbol(n)?).copied(),
            ExprKind::Conversion { operand, .. } => self.eval(operand, env),
            ExprKind::Unary { op, operand } => {
                let v = self.eval(operand, env)?;
                match op {
                    UnOp::Neg | UnOp::Minus => v.checked_neg(),
                    UnOp::Not => Some(i64::from(v == 0)),
                    UnOp::BitNot => Some(!v),
                    UnOp::User(_) => None,
                }
            }
            ExprKind::Binary { op, lhs, rhs } => {
                let (a, b) = (self.eval(lhs, env)?, self.eval(rhs, env)?);
                binary(*op, a, b)
            }
            _ => None,
        }
    }
}

fn binary(op: BinOp, a: i64, b: i64) -> Option<i64> {
    use BinOp::*;
    Some(match op {
        Add | Plus => a.checked_add(b)?,
        Sub | Minus => a.checked_sub(b)?,
        Mul | Times => a.checked_mul(b)?,
        Div => a.checked_div(b)?,
        Rem => a.checked_rem(b)?,
        BitAnd => a & b,
        BitOr => a | b,
        Xor => a ^ b,
        Shl => a.checked_shl(u32::try_from(b).ok()?)?,
        Shr => a.checked_shr(u32::try_from(b).ok()?)?,
        And => i64::from(a != 0 && b != 0),
        Or => i64::from(a != 0 || b != 0),
        Eq => i64::from(a == b),
        Ne => i64::from(a != b),
        Lt => i64::from(a < b),
        Gt => i64::from(a > b),
        Le => i64::from(a <= b),
        Ge => i64::from(a >= b),
        _ => return None,
    })
}

/// The dimensions of a channel or (fixed-size) channel array type; `None` for other types.
fn chan_dims(t: &Type) -> Option<Vec<u32>> {
    match t {
        Type::Chan(..) => Some(Vec::new()),
        Type::Array(Some(n), inner) => {
            let mut d = vec![*n];
            d.extend(chan_dims(inner)?);
            Some(d)
        }
        _ => None,
    }
}

/// The body of the PROCESSOR process at `span` under the PLACED PAR `p`.
pub fn processor_body(p: &Process, span: Span) -> Option<&Process> {
    match &p.kind {
        ProcessKind::Processor { body, .. } if p.span == span => Some(body),
        ProcessKind::Par { body, .. } => body.iter().find_map(|q| processor_body(q, span)),
        _ => None,
    }
}

/// The declarations and processes directly inside `p`.
fn children(p: &Process) -> (Vec<&ast::Decl>, Vec<&Process>) {
    let (mut decls, mut procs) = (Vec::new(), Vec::new());
    match &p.kind {
        ProcessKind::Scope { decls: ds, body } => {
            decls.extend(ds);
            procs.push(&**body);
        }
        ProcessKind::Seq { body, .. } | ProcessKind::Par { body, .. } => procs.extend(body),
        ProcessKind::Processor { body, .. } | ProcessKind::While { body, .. } => {
            procs.push(&**body)
        }
        ProcessKind::If { choices, .. } => {
            for c in choices {
                decls.extend(&c.decls);
                match &c.kind {
                    ChoiceKind::Guarded { body, .. } => procs.push(body),
                    ChoiceKind::Nested(q) => procs.push(&**q),
                }
            }
        }
        ProcessKind::Case { options, .. } => {
            for o in options {
                decls.extend(&o.decls);
                procs.push(&o.body);
            }
        }
        ProcessKind::CaseInput { variants, .. } => {
            for v in variants {
                decls.extend(&v.decls);
                procs.push(&v.body);
            }
        }
        ProcessKind::Alt(alt) => alt_children(alt, &mut decls, &mut procs),
        ProcessKind::Extended {
            input,
            during,
            after,
        } => {
            procs.push(&**input);
            procs.push(&**during);
            procs.extend(after.as_deref());
        }
        _ => {}
    }
    (decls, procs)
}

fn alt_children<'p>(
    alt: &'p ast::Alt,
    decls: &mut Vec<&'p ast::Decl>,
    procs: &mut Vec<&'p Process>,
) {
    for a in &alt.alternatives {
        decls.extend(&a.decls);
        match &a.kind {
            AltKind::Guarded { guard, body, .. } => {
                procs.push(&**guard);
                procs.push(&**body);
            }
            AltKind::CaseInput { variants, .. } => {
                for v in variants {
                    decls.extend(&v.decls);
                    procs.push(&v.body);
                }
            }
            AltKind::Nested(inner) => alt_children(inner, decls, procs),
        }
    }
}

/// The walk of one processor instance's body, recording its uses of configuration channels.
struct Walk<'c, 'a> {
    cx: &'c mut Config<'a>,
    channels: &'c FxHashMap<SymbolId, Vec<u32>>,
    host: &'c [SymbolId],
    processor: usize,
    /// Abbreviations declared in the body that name configuration channels.
    aliases: FxHashMap<SymbolId, Target>,
    uses: &'c mut BTreeMap<(SymbolId, u32), Vec<Use>>,
}

impl Walk<'_, '_> {
    fn process(&mut self, p: &Process, env: &mut Env) {
        match &p.kind {
            ProcessKind::Output { chan, .. } => self.use_chan(chan, Mode::Output, env),
            ProcessKind::Input { chan, .. } => self.use_chan(chan, Mode::Input, env),
            ProcessKind::CaseInput { chan, variants } => {
                self.use_chan(chan, Mode::Input, env);
                for v in variants {
                    self.decls(&v.decls, env);
                    self.process(&v.body, env);
                }
            }
            ProcessKind::Call { name, args } => self.call(name, args, env),
            ProcessKind::Scope { decls, body } => {
                self.decls(decls, env);
                self.process(body, env);
            }
            ProcessKind::Seq {
                repl: Some(r),
                body,
            }
            | ProcessKind::Par {
                repl: Some(r),
                body,
                ..
            } => self.replicated(r, env, |w, env| body.iter().for_each(|q| w.process(q, env))),
            ProcessKind::If { repl, choices } => match repl {
                Some(r) => self.replicated(r, env, |w, env| {
                    w.choices(choices, env);
                }),
                None => {
                    self.choices(choices, env);
                }
            },
            ProcessKind::Case { selector, options } => {
                let sel = self.cx.eval(selector, env);
                for o in options {
                    let chosen = match (&o.values, sel) {
                        (_, None) | (None, _) => true,
                        (Some(vs), Some(s)) => vs
                            .iter()
                            .any(|v| self.cx.eval(v, env).is_none_or(|v| v == s)),
                    };
                    if chosen {
                        self.decls(&o.decls, env);
                        self.process(&o.body, env);
                        if sel.is_some() {
                            break;
                        }
                    }
                }
            }
            ProcessKind::Alt(alt) => self.alt(alt, env),
            _ => {
                let (decls, procs) = children(p);
                for d in decls {
                    self.decls(std::slice::from_ref(d), env);
                }
                for q in procs {
                    self.process(q, env);
                }
            }
        }
    }

    fn alt(&mut self, alt: &ast::Alt, env: &mut Env) {
        let run = |w: &mut Self, env: &mut Env| {
            for a in &alt.alternatives {
                w.decls(&a.decls, env);
                match &a.kind {
                    AltKind::Guarded { cond, guard, body } => {
                        if cond.as_ref().and_then(|c| w.cx.eval(c, env)) == Some(0) {
                            continue;
                        }
                        w.process(guard, env);
                        w.process(body, env);
                    }
                    AltKind::CaseInput {
                        cond,
                        chan,
                        variants,
                    } => {
                        if cond.as_ref().and_then(|c| w.cx.eval(c, env)) == Some(0) {
                            continue;
                        }
                        w.use_chan(chan, Mode::Input, env);
                        for v in variants {
                            w.decls(&v.decls, env);
                            w.process(&v.body, env);
                        }
                    }
                    AltKind::Nested(inner) => w.alt(inner, env),
                }
            }
        };
        match &alt.repl {
            Some(r) => self.replicated(r, env, run),
            None => run(self, env),
        }
    }

    /// Walks the choices of an IF in order: a constant TRUE condition ends the walk there, a
    /// constant FALSE one is passed over, any other is walked and the walk goes on.
    fn choices(&mut self, choices: &[ast::Choice], env: &mut Env) -> bool {
        for c in choices {
            self.decls(&c.decls, env);
            match &c.kind {
                ChoiceKind::Guarded { cond, body } => match self.cx.eval(cond, env) {
                    Some(0) => {}
                    Some(_) => {
                        self.process(body, env);
                        return true;
                    }
                    None => self.process(body, env),
                },
                ChoiceKind::Nested(q) => {
                    if let ProcessKind::If {
                        repl: None,
                        choices,
                    } = &q.kind
                    {
                        if self.choices(choices, env) {
                            return true;
                        }
                    } else {
                        self.process(q, env);
                    }
                }
            }
        }
        false
    }

    /// Runs `body` once per value of `r` when its base and count are known (and not too many),
    /// else once with the index unknown.
    fn replicated(
        &mut self,
        r: &ast::Replicator,
        env: &mut Env,
        mut body: impl FnMut(&mut Self, &mut Env),
    ) {
        let Some(sym) = self.cx.symbol(&r.name) else {
            return;
        };
        let base = self.cx.eval(&r.base, env);
        let count = self.cx.eval(&r.count, env);
        let step = r.step.as_ref().map_or(Some(1), |s| self.cx.eval(s, env));
        match (base, count, step) {
            (Some(b), Some(n), Some(s)) if (0..=MAX_UNROLL).contains(&n) => {
                for k in 0..n {
                    env.insert(sym, b + k * s);
                    body(self, env);
                }
                env.remove(&sym);
            }
            _ => body(self, env),
        }
    }

    fn decls(&mut self, decls: &[ast::Decl], env: &mut Env) {
        for d in decls {
            match &d.kind {
                DeclKind::Abbrev { name, value, .. } => {
                    if let (Some(sym), Some(t)) = (self.cx.symbol(name), self.target(value, env)) {
                        self.aliases.insert(sym, t);
                    }
                }
                DeclKind::Proc { .. } | DeclKind::Function { .. } => {}
                _ => {}
            }
        }
    }

    /// Records a use of `chan` (if it names configuration channels) in `mode`.
    fn use_chan(&mut self, chan: &Expr, mode: Mode, env: &Env) {
        if let Some(t) = self.target(chan, env) {
            self.record(&t, mode, chan.span);
        }
    }

    fn record(&mut self, t: &Target, mode: Mode, span: Span) {
        for &e in &t.elements {
            self.uses.entry((t.channel, e)).or_default().push(Use {
                processor: self.processor,
                mode,
                span,
            });
        }
    }

    fn call(&mut self, name: &ast::Name, args: &[Expr], env: &Env) {
        let Some(sym) = self.cx.symbol(name) else {
            return;
        };
        let SymbolKind::Proc(pid) = self.cx.checked.symbols[sym].kind else {
            return;
        };
        let info = &self.cx.checked.procs[pid];
        for (i, a) in args.iter().enumerate() {
            let Some(t) = self.target(a, env) else {
                continue;
            };
            let Some(&param) = info.params.get(i) else {
                continue;
            };
            for mode in self.param_modes(param, &info.usage) {
                self.record(&t, mode, a.span);
            }
        }
    }

    /// Which ways a PROC uses a channel parameter: its specifier, else its usage summary.
    fn param_modes(&self, param: SymbolId, usage: &[crate::usage::Access]) -> Vec<Mode> {
        let mut t = &self.cx.checked.symbols[param].ty;
        while let Type::Array(_, inner) = t {
            t = inner;
        }
        match t {
            Type::Chan(_, Direction::Input) => vec![Mode::Input],
            Type::Chan(_, Direction::Output) => vec![Mode::Output],
            _ => {
                let mut m: Vec<Mode> = usage
                    .iter()
                    .filter(|a| a.symbol == param && matches!(a.mode, Mode::Input | Mode::Output))
                    .map(|a| a.mode)
                    .collect();
                m.sort_by_key(|m| *m as u8);
                m.dedup();
                m
            }
        }
    }

    /// The configuration channel elements `e` denotes, if any. A subscript that cannot be
    /// evaluated is reported.
    fn target(&mut self, e: &Expr, env: &Env) -> Option<Target> {
        match &e.kind {
            ExprKind::Directed { chan, .. } => self.target(chan, env),
            ExprKind::Name(n) => {
                let sym = self.cx.symbol(n)?;
                if let Some(t) = self.aliases.get(&sym) {
                    return Some(t.clone());
                }
                if self.host.contains(&sym) {
                    if self.processor != 0 {
                        self.cx.diags.push(error(
                            format!(
                                "`{}` is a channel of the host, which is connected to the root processor only",
                                n.text
                            ),
                            "the root is the lowest-numbered PROCESSOR: send the data there over links",
                            n.span,
                        ));
                    }
                    return None;
                }
                let dims = self.channels.get(&sym)?;
                let count: u32 = dims.iter().product();
                Some(Target {
                    channel: sym,
                    elements: (0..count).collect(),
                })
            }
            ExprKind::Subscript { base, index } => {
                let t = self.target(base, env)?;
                let chunk = self.chunk(&t, base)?;
                let Some(i) = self.cx.eval(index, env) else {
                    self.unknown(base, index.span);
                    return None;
                };
                let lo = usize::try_from(i).ok()?.checked_mul(chunk)?;
                Some(Target {
                    channel: t.channel,
                    elements: t.elements.get(lo..lo + chunk)?.to_vec(),
                })
            }
            ExprKind::Slice { base, from, count } => {
                let t = self.target(base, env)?;
                let chunk = self.chunk(&t, base)?;
                let f = match from {
                    Some(f) => self.cx.eval(f, env),
                    None => Some(0),
                };
                let n = match count {
                    Some(c) => self.cx.eval(c, env),
                    None => f.map(|f| (t.elements.len() / chunk) as i64 - f),
                };
                let (Some(f), Some(n)) = (f, n) else {
                    self.unknown(base, e.span);
                    return None;
                };
                let lo = usize::try_from(f).ok()? * chunk;
                let hi = lo + usize::try_from(n).ok()? * chunk;
                Some(Target {
                    channel: t.channel,
                    elements: t.elements.get(lo..hi)?.to_vec(),
                })
            }
            _ => None,
        }
    }

    /// Elements per index step of the array `base` (whose elements are `t`).
    fn chunk(&self, t: &Target, base: &Expr) -> Option<usize> {
        let len = match self.cx.checked.expr_types.get(&base.span) {
            Some(Type::Array(Some(n), _)) => *n as usize,
            _ => return None,
        };
        (len > 0).then(|| t.elements.len() / len)
    }

    fn unknown(&mut self, base: &Expr, span: Span) {
        self.cx.diags.push(error(
            format!(
                "cannot tell which element of `{}` this is when the network is configured",
                root_name(base)
            ),
            "a channel that may be a link needs a subscript computed from constants and replicator indices",
            span,
        ));
    }
}

/// The name at the root of a channel expression, for messages.
fn root_name(e: &Expr) -> String {
    match &e.kind {
        ExprKind::Name(n) => n.text.clone(),
        ExprKind::Subscript { base, .. } | ExprKind::Slice { base, .. } => root_name(base),
        ExprKind::Directed { chan, .. } => root_name(chan),
        _ => "this channel".into(),
    }
}
