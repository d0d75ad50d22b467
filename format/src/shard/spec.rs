//! Which share of a store's cubes a shard holds.

use crate::Error;

/// Which share of the cubes a shard holds: `index` of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardSpec {
    index: u32,
    count: u32,
}

impl ShardSpec {
    /// The shard's index `I`.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// The number of shards `N`.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Shard `index` of `count`; [`Error::InvalidShardSpec`] unless `index < count`.
    pub fn new(index: u32, count: u32) -> Result<Self, Error> {
        if count == 0 || index >= count {
            return Err(Error::InvalidShardSpec(format!("{index}/{count}")));
        }
        Ok(ShardSpec { index, count })
    }

    /// How many of a store's `total` cubes this shard holds.
    pub fn cubes_of(&self, total: u32) -> u32 {
        if self.index >= total {
            0
        } else {
            (total - 1 - self.index) / self.count + 1
        }
    }

    /// The store's index of this shard's `k`-th cube (`k < cubes_of(total)`).
    pub fn cube(&self, k: u32) -> u32 {
        let i = u64::from(self.index) + u64::from(k) * u64::from(self.count);
        u32::try_from(i).unwrap_or(u32::MAX)
    }
}

impl std::fmt::Display for ShardSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl std::str::FromStr for ShardSpec {
    type Err = Error;
    /// Parses `I/N`.
    fn from_str(s: &str) -> Result<Self, Error> {
        let bad = || Error::InvalidShardSpec(s.to_string());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let i = i.trim().parse().map_err(|_| bad())?;
        let n = n.trim().parse().map_err(|_| bad())?;
        ShardSpec::new(i, n).map_err(|_| bad())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_cubes() {
        for total in [0u32, 1, 2, 25, 100] {
            for count in [1u32, 2, 3, 7, 30, 200] {
                let mut seen = vec![0u32; total as usize];
                for index in 0..count {
                    let spec = ShardSpec::new(index, count).unwrap();
                    let n = spec.cubes_of(total);
                    for k in 0..n {
                        let i = spec.cube(k);
                        assert_eq!(i % count, index);
                        seen[i as usize] += 1;
                    }
                    assert!(n <= total.div_ceil(count));
                }
                assert!(
                    seen.iter().all(|&n| n == 1),
                    "{total} cubes, {count} shards"
                );
            }
        }
    }

    #[test]
    fn shard_specs_parse_and_refuse() {
        let s: ShardSpec = "3/8".parse().unwrap();
        assert_eq!((s.index(), s.count()), (3, 8));
        assert_eq!(s.to_string(), "3/8");
        for bad in ["8/8", "0/0", "1", "a/2", "1/b", "-1/2", ""] {
            let e = bad.parse::<ShardSpec>().unwrap_err().to_string();
            assert!(e.contains(&format!("{bad:?}")), "{e}");
        }
    }
}
