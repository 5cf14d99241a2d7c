//! Endpoints: channel words that a host stream or a link stands behind.
//!
//! Such a channel word permanently holds `endpoint | TAG_ENDPOINT`, where `endpoint` is an
//! [`Endpoint`] owned by the node (boxed, so its address is stable). `rt_in`/`rt_out`/ALT find the
//! tag and call the endpoint's engine here instead of parking in the word. Compiled code does not
//! know the difference: it passes the channel word's address as for any channel.

use crate::abi::{Status, Word, Wptr, tag, wait};
use crate::error::ErrorKind;
use crate::host::HostStream;
use crate::keyboard::{Keyboard, Took};
use crate::link::LinkEnd;
use crate::node::Node;

/// What stands behind an endpoint's channel word.
#[derive(Debug)]
pub(crate) enum Engine {
    /// The host's input (`keyboard`).
    HostIn,
    /// A host output stream (`screen`, `error`).
    HostOut(HostStream),
    /// The sending end of a link.
    LinkOut(LinkEnd),
    /// The receiving end of a link.
    LinkIn(LinkEnd),
    /// A link (or host channel) that nothing is connected to: communication waits for ever.
    Unconnected,
}

/// An endpoint and the channel word that designates it.
#[derive(Debug)]
#[repr(align(8))]
pub(crate) struct Endpoint {
    pub(crate) engine: Engine,
    /// The channel word compiled code uses: `self as *const _ | TAG_ENDPOINT`.
    pub(crate) word: Word,
    /// A name for reports (`screen`, `link 0 out`...).
    pub(crate) name: String,
}

/// The name of the endpoint designated by the ENDPOINT-tagged word `w`.
///
/// # Safety
/// `w` was made by [`Node::add_endpoint`] on a node that is still alive.
pub(crate) unsafe fn endpoint_name(w: Word) -> String {
    // SAFETY: caller contract.
    unsafe { (*((w & !tag::MASK) as *const Endpoint)).name.clone() }
}

impl Node {
    /// Registers an endpoint and returns the address of its channel word.
    pub(crate) fn add_endpoint(&mut self, engine: Engine, name: &str) -> *mut Word {
        let mut ext = Box::new(Endpoint {
            engine,
            word: 0,
            name: name.to_string(),
        });
        ext.word = (&*ext as *const Endpoint as Word) | tag::ENDPOINT;
        let chan = &mut ext.word as *mut Word;
        self.endpoints.push(ext);
        chan
    }

    /// Binds the top-level PROC's byte channels: returns the channel words of `keyboard`,
    /// `screen` and `error`, in that order. Pass them as the main PROC's channel parameters.
    pub fn host_channels(&mut self) -> [*mut Word; 3] {
        [
            self.add_endpoint(Engine::HostIn, "keyboard"),
            self.add_endpoint(Engine::HostOut(HostStream::Screen), "screen"),
            self.add_endpoint(Engine::HostOut(HostStream::Error), "error"),
        ]
    }

    /// The endpoint designated by the tagged word `w`.
    ///
    /// # Safety
    /// `w` is an ENDPOINT-tagged word created by [`Node::add_endpoint`] on this node.
    unsafe fn endpoint(&mut self, w: Word) -> &mut Endpoint {
        // SAFETY: caller contract; the endpoint is boxed and owned by `self.endpoints`.
        unsafe { &mut *((w & !tag::MASK) as *mut Endpoint) }
    }

    /// `rt_in` on an endpoint channel.
    ///
    /// # Safety
    /// As for `rt_in`; `w` is the channel's ENDPOINT-tagged word.
    pub(crate) unsafe fn endpoint_in(
        &mut self,
        ws: Wptr,
        chan: *mut Word,
        w: Word,
        data: *mut u8,
        len: Word,
    ) -> Status {
        // SAFETY: caller contract.
        let engine = unsafe { &self.endpoint(w).engine } as *const Engine;
        // SAFETY: `data` is valid for `len` bytes (rt_in contract); the endpoint outlives the call.
        unsafe {
            let buf = std::slice::from_raw_parts_mut(data, len.max(0) as usize);
            match &*engine {
                Engine::HostIn => match self.threaded_keyboard() {
                    Some(kb) => self.keyboard_in(&kb, ws, chan, data, buf.len()),
                    None => {
                        let r = self.host.read(buf);
                        self.host_result(ws, r)
                    }
                },
                Engine::LinkIn(end) => self.link_in(end, ws, chan as Word, data, len),
                Engine::Unconnected => self.wait_forever(ws, chan as Word),
                _ => self.protocol_error(ws),
            }
        }
    }

    /// `rt_out` on an endpoint channel.
    ///
    /// # Safety
    /// As for `rt_out`; `w` is the channel's ENDPOINT-tagged word.
    pub(crate) unsafe fn endpoint_out(
        &mut self,
        ws: Wptr,
        chan: *mut Word,
        w: Word,
        data: *mut u8,
        len: Word,
    ) -> Status {
        // SAFETY: caller contract.
        let engine = unsafe { &self.endpoint(w).engine } as *const Engine;
        // SAFETY: `data` is valid for `len` bytes (rt_out contract); the endpoint outlives the
        // call.
        unsafe {
            let buf = std::slice::from_raw_parts(data, len.max(0) as usize);
            match &*engine {
                Engine::HostOut(stream) => {
                    let r = self.host.write(*stream, buf);
                    self.host_result(ws, r)
                }
                Engine::LinkOut(end) => {
                    self.link_out(end, ws, chan as Word | wait::OUTPUT, data, len)
                }
                Engine::Unconnected => self.wait_forever(ws, chan as Word | wait::OUTPUT),
                _ => self.protocol_error(ws),
            }
        }
    }

    /// `enbc` on an endpoint channel: whether input is ready now (else the ALTer is registered
    /// to be woken).
    ///
    /// # Safety
    /// `ws` is the ALTing frame; `w` an ENDPOINT-tagged word of this node.
    pub(crate) unsafe fn endpoint_enable(&mut self, ws: Wptr, w: Word) -> bool {
        // SAFETY: caller contract.
        let engine = unsafe { &self.endpoint(w).engine } as *const Engine;
        // SAFETY: the endpoint outlives the call.
        match unsafe { &*engine } {
            Engine::HostIn => match self.threaded_keyboard() {
                Some(kb) => {
                    let ready = kb.enable(self.desc(ws) | tag::ALT, &self.mailbox);
                    if !ready {
                        self.link_waiters += 1;
                    }
                    ready
                }
                None => true,
            },
            Engine::LinkIn(end) => self.link_enable(end, ws),
            _ => false,
        }
    }

    /// `disc` on an endpoint channel: whether input is ready (and unregisters the ALTer).
    ///
    /// # Safety
    /// As for [`Node::endpoint_enable`].
    pub(crate) unsafe fn endpoint_disable(&mut self, ws: Wptr, w: Word) -> bool {
        // SAFETY: caller contract.
        let engine = unsafe { &self.endpoint(w).engine } as *const Engine;
        // SAFETY: the endpoint outlives the call.
        match unsafe { &*engine } {
            Engine::HostIn => match self.threaded_keyboard() {
                Some(kb) => {
                    let me = self.desc(ws) | tag::ALT;
                    let (withdrawn, ready) = kb.disable(me);
                    if withdrawn {
                        self.link_waiters -= 1;
                    } else {
                        // As for a link: a wake-up already posted is in the mailbox by now.
                        self.deliver_mail_except(me);
                    }
                    ready
                }
                None => true,
            },
            Engine::LinkIn(end) => self.link_disable(end, ws),
            _ => false,
        }
    }

    /// The keyboard thread, for a node outside a network whose host reads the input on one.
    fn threaded_keyboard(&mut self) -> Option<Keyboard> {
        if self.net.is_some() {
            return None;
        }
        self.host.keyboard()
    }

    /// An input on the threaded keyboard: complete at once if the bytes are there, else the
    /// process blocks until the keyboard thread posts it.
    ///
    /// # Safety
    /// As for `rt_in`.
    unsafe fn keyboard_in(
        &mut self,
        kb: &Keyboard,
        ws: Wptr,
        chan: *mut Word,
        data: *mut u8,
        len: usize,
    ) -> Status {
        let flushed = self.host.flush_screen();
        if flushed.is_err() {
            return self.host_result(ws, flushed);
        }
        // SAFETY: `data` is the blocked frame's buffer, valid until it is posted or withdrawn
        // (see `withdraw_keyboard`).
        match unsafe { kb.input(self.desc(ws), data, len, &self.mailbox) } {
            Took::Done => self.host_result(ws, Ok(())),
            Took::Waiting => {
                self.stats.communications += 1;
                // SAFETY: `ws` is the running frame.
                unsafe { self.note_blocked(ws, chan as Word) };
                self.link_waiters += 1;
                Status::BLOCKED
            }
        }
    }

    /// Withdraws what this node's frames have registered with the keyboard thread (the node
    /// stops: their workspaces are about to go).
    pub(crate) fn withdraw_keyboard(&mut self) {
        if let Some(kb) = self.host.started_keyboard() {
            let n = kb.withdraw(&self.mailbox);
            self.link_waiters -= n;
        }
    }

    fn host_result(&mut self, ws: Wptr, r: std::io::Result<()>) -> Status {
        match r {
            Ok(()) => {
                self.stats.communications += 1;
                Status::DONE
            }
            // SAFETY: `ws` is the running frame.
            Err(_) => unsafe { crate::error::rt_error(self, ws, ErrorKind::Host as Word, -1) },
        }
    }

    /// Blocks the running process on an unconnected channel: nothing will ever wake it, so it
    /// shows in the node's deadlock report.
    fn wait_forever(&mut self, ws: Wptr, what: Word) -> Status {
        // SAFETY: `ws` is the running frame.
        unsafe { self.note_blocked(ws, what) };
        Status::BLOCKED
    }

    fn protocol_error(&mut self, ws: Wptr) -> Status {
        // SAFETY: `ws` is the running frame.
        unsafe { crate::error::rt_error(self, ws, ErrorKind::Host as Word, -1) }
    }
}
