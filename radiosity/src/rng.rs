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
    pub fn advance(&mut self, delta: u64) {
        let stride = self.stride(delta);
        self.leap(stride);
    }

    /// The jump over `delta` outputs of a generator of this one's stream ([`Pcg32::advance`]
    /// takes it at once; [`SetStrides`] keeps a table of them).
    pub fn stride(&self, mut delta: u64) -> Stride {
        let (mut mult, mut plus) = (MULTIPLIER, self.inc);
        let mut acc = Stride::NONE;
        while delta > 0 {
            if delta & 1 == 1 {
                acc = acc.then(Stride { mult, plus });
            }
            plus = mult.wrapping_add(1).wrapping_mul(plus);
            mult = mult.wrapping_mul(mult);
            delta >>= 1;
        }
        acc
    }

    /// Takes the jump `stride`, found by [`Pcg32::stride`] on a generator of the same stream.
    pub fn leap(&mut self, stride: Stride) {
        self.state = stride
            .mult
            .wrapping_mul(self.state)
            .wrapping_add(stride.plus);
    }

    /// Returns a uniform `f32` in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

/// A jump of a generator's state over some outputs (`state -> mult * state + plus`, modulo
/// 2^64): the same for every generator of one stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stride {
    mult: u64,
    plus: u64,
}

impl Stride {
    /// No jump.
    pub const NONE: Stride = Stride { mult: 1, plus: 0 };

    /// This jump, then `next` (jumps of one stream commute: they are powers of one step).
    pub fn then(self, next: Stride) -> Stride {
        Stride {
            mult: next.mult.wrapping_mul(self.mult),
            plus: next.mult.wrapping_mul(self.plus).wrapping_add(next.plus),
        }
    }
}

/// The jumps over `set * skip` outputs of one stream for every set below 256, from two tables
/// of 16 (a set's low and high hex digit): receivers each skip the sample sets before theirs
/// ([`crate::solver::receiver_seed`]) with one composition instead of [`Pcg32::advance`]'s
/// dozen steps. Taking [`SetStrides::of`] leaves a generator where `advance(set * skip)` would.
pub struct SetStrides {
    low: [Stride; 16],
    high: [Stride; 16],
    skip: u64,
    stream: Pcg32,
}

impl SetStrides {
    /// The table for generators of `stream`'s stream, sets `skip` outputs apart.
    pub fn new(stream: &Pcg32, skip: u64) -> SetStrides {
        let (one, sixteen) = (stream.stride(skip), stream.stride(16 * skip));
        let mut low = [Stride::NONE; 16];
        let mut high = [Stride::NONE; 16];
        for i in 1..16 {
            low[i] = low[i - 1].then(one);
            high[i] = high[i - 1].then(sixteen);
        }
        SetStrides {
            low,
            high,
            skip,
            stream: stream.clone(),
        }
    }

    /// The jump over `set * skip` outputs.
    pub fn of(&self, set: usize) -> Stride {
        if set < 256 {
            self.low[set % 16].then(self.high[set / 16])
        } else {
            self.stream.stride(set as u64 * self.skip)
        }
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

    #[test]
    fn set_strides_jump_as_far_as_advance() {
        let stream = Pcg32::new(0, 0x5eed);
        for skip in [1u64, 18, 32, 512] {
            let table = SetStrides::new(&stream, skip);
            for set in [0usize, 1, 15, 16, 17, 100, 255, 256, 1000] {
                let mut advanced = Pcg32::new(41, 0x5eed);
                advanced.advance(set as u64 * skip);
                let mut leapt = Pcg32::new(41, 0x5eed);
                leapt.leap(table.of(set));
                assert_eq!(
                    leapt.next_u32(),
                    advanced.next_u32(),
                    "skip {skip} set {set}"
                );
            }
        }
    }
}
