//! The implementations of the runtime [`Entry`] points that [`crate::abi`] declares.

use crate::abi::Entry;
use crate::alt::{
    rt_alt, rt_altend, rt_altwt, rt_disc, rt_diss, rt_dist, rt_enbc, rt_enbs, rt_enbt, rt_talt,
    rt_taltwt,
};
use crate::arena::{rt_addr_ok, rt_vector_free, rt_vector_get};
use crate::chan::{rt_in, rt_out, rt_preempt, rt_xend, rt_xin, rt_xwait};
use crate::error::rt_error;
use crate::par::{rt_endp, rt_par_wait, rt_startp, rt_startp_pri, rt_stopp};
use crate::placement::rt_placement;
use crate::sched::{rt_reschedule, rt_timeslice};
use crate::timer::{rt_timer_read, rt_tin};

/// The address of entry `e`'s implementation (an `extern "C"` function of its signature).
pub fn address(e: Entry) -> *const u8 {
    match e {
        Entry::In => rt_in as *const u8,
        Entry::Out => rt_out as *const u8,
        Entry::Preempt => rt_preempt as *const u8,
        Entry::Startp => rt_startp as *const u8,
        Entry::StartpPri => rt_startp_pri as *const u8,
        Entry::Endp => rt_endp as *const u8,
        Entry::ParWait => rt_par_wait as *const u8,
        Entry::Stopp => rt_stopp as *const u8,
        Entry::Timeslice => rt_timeslice as *const u8,
        Entry::Reschedule => rt_reschedule as *const u8,
        Entry::TimerRead => rt_timer_read as *const u8,
        Entry::Tin => rt_tin as *const u8,
        Entry::Alt => rt_alt as *const u8,
        Entry::Talt => rt_talt as *const u8,
        Entry::Enbc => rt_enbc as *const u8,
        Entry::Enbs => rt_enbs as *const u8,
        Entry::Enbt => rt_enbt as *const u8,
        Entry::Altwt => rt_altwt as *const u8,
        Entry::Taltwt => rt_taltwt as *const u8,
        Entry::Disc => rt_disc as *const u8,
        Entry::Diss => rt_diss as *const u8,
        Entry::Dist => rt_dist as *const u8,
        Entry::Altend => rt_altend as *const u8,
        Entry::Error => rt_error as *const u8,
        Entry::Placement => rt_placement as *const u8,
        Entry::Xwait => rt_xwait as *const u8,
        Entry::Xin => rt_xin as *const u8,
        Entry::Xend => rt_xend as *const u8,
        Entry::AddrOk => rt_addr_ok as *const u8,
        Entry::VectorGet => rt_vector_get as *const u8,
        Entry::VectorFree => rt_vector_free as *const u8,
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn every_entry_has_a_distinct_implementation() {
        for (i, e) in Entry::ALL.iter().enumerate() {
            assert!(!address(*e).is_null());
            assert!(
                Entry::ALL[..i].iter().all(|o| address(*o) != address(*e)),
                "{:?} shares an implementation",
                e
            );
        }
    }
}
