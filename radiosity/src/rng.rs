//! A small, seedable pseudo-random generator (PCG-XSH-RR 32), so that every run and every test is
//! reproducible without a dependency.

/// The LCG multiplier of PCG32.
const MULTIPLIER: u64 = 6364136223846793005;

/// PCG32 state.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// Creates a generator from a seed and a stream number.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// Returns the next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULTIPLIER).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Skips `delta` outputs in O(log delta) steps: afterwards the generator is where `delta`
    /// calls of [`Pcg32::next_u32`] would have left it (Brown, "Random number generation with
    /// arbitrary strides", 1994).
    pub fn advance(&mut self, mut delta: u64) {
        let (mut mult, mut plus) = (MULTIPLIER, self.inc);
        let (mut acc_mult, mut acc_plus) = (1u64, 0u64);
        while delta > 0 {
            if delta & 1 == 1 {
                acc_mult = acc_mult.wrapping_mul(mult);
                acc_plus = acc_plus.wrapping_mul(mult).wrapping_add(plus);
            }
            plus = mult.wrapping_add(1).wrapping_mul(plus);
            mult = mult.wrapping_mul(mult);
            delta >>= 1;
        }
        self.state = acc_mult.wrapping_mul(self.state).wrapping_add(acc_plus);
    }

    /// Returns a uniform `f32` in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn advance_skips_exactly_that_many_outputs() {
        for delta in [0u64, 1, 2, 7, 64, 1000, 4591] {
            let mut stepped = Pcg32::new(99, 0x5eed);
            for _ in 0..delta {
                stepped.next_u32();
            }
            let mut jumped = Pcg32::new(99, 0x5eed);
            jumped.advance(delta);
            assert_eq!(jumped.next_u32(), stepped.next_u32(), "delta {delta}");
        }
    }
}
