//! Shrinking a failing input: delta debugging over lines (an OBJ face or vertex, a TOML key),
//! then over bytes, keeping every cut after which the input still fails.

/// The smallest input found, by removing chunks of `input` (lines first, then bytes, halving
/// the chunk size down to 1) while `fails` still holds. `fails(input)` must be true.
///
/// ```
/// use subdiv_fuzz::reduce::reduce;
///
/// // Fails whenever `f 1 2 3` and a `v` remain: the lines go, then the bytes.
/// let input = b"v 0 0 0\nv 1 0 0\n# note\nf 1 2 3\nvt 0 0\n";
/// let fails = |b: &[u8]| {
///     let t = String::from_utf8_lossy(b);
///     t.contains("f 1 2 3") && t.contains('v')
/// };
/// assert_eq!(reduce(input, fails), b"f 1 2 3v");
/// ```
pub fn reduce(input: &[u8], mut fails: impl FnMut(&[u8]) -> bool) -> Vec<u8> {
    let lines: Vec<Vec<u8>> = input.split_inclusive(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    let lines = minimise(lines, &mut |parts: &[Vec<u8>]| fails(&parts.concat()));
    let bytes: Vec<Vec<u8>> = lines.concat().into_iter().map(|b| vec![b]).collect();
    minimise(bytes, &mut |parts: &[Vec<u8>]| fails(&parts.concat())).concat()
}

/// ddmin over `parts`: remove runs of `chunk` parts while the rest still fails, halving
/// `chunk` when no run can go.
fn minimise(mut parts: Vec<Vec<u8>>, fails: &mut impl FnMut(&[Vec<u8>]) -> bool) -> Vec<Vec<u8>> {
    let mut chunk = parts.len().div_ceil(2).max(1);
    loop {
        let mut removed = false;
        let mut start = 0;
        while start < parts.len() {
            let end = (start + chunk).min(parts.len());
            let rest: Vec<Vec<u8>> = parts[..start].iter().chain(&parts[end..]).cloned().collect();
            if fails(&rest) {
                parts = rest;
                removed = true;
            } else {
                start = end;
            }
        }
        if chunk == 1 && !removed {
            return parts;
        }
        if !removed {
            chunk = chunk.div_ceil(2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduces_to_a_one_minimal_input() {
        // Fails when the bytes `a` and `z` both remain, in that order.
        let fails = |b: &[u8]| b.iter().position(|&c| c == b'a').is_some_and(|i| b[i..].contains(&b'z'));
        let input = b"xxa\nyyy\nqqz\nrr";
        let out = reduce(input, fails);
        assert_eq!(out, b"az");
        // Nothing can go: the input stays.
        assert_eq!(reduce(b"az", fails), b"az");
    }
}
