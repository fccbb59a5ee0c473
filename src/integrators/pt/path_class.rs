//! Path classes for `--path-filter` of `pt` and `pt-cf` (a diagnostic: which light paths carry a
//! scene's light and noise, and which of them guiding helps).
//!
//! A path's class is its vertex sequence from the camera to the light in three tokens: `D` a
//! non-Dirac vertex, `S` a run of Dirac vertices (mirror, glass: one `S` however long the chain),
//! `L` the light (an emitter hit or a next-event sample). So `DL` is direct light, `DSL` a caustic
//! seen directly, `SDSL` one seen through glass, `DDSL` a wall lit by a floor caustic. A filter
//! is a comma list of patterns, each a class (ending in `L`) or a prefix ending in `*` (`DS*`);
//! the path tracer then adds only the contributions whose class matches, drawing the same random
//! numbers as without a filter, so the images of filters that partition the classes (say
//! `L,S*,D*`) sum to the unfiltered image rendered with `--emission-split 1` (a non-finite
//! sample, which the film zeroes whole, is zeroed only in the part that carries it).
//!
//! A filter turns emission splitting off (`PtArgs::split`): the split's extra camera rays add
//! light of classes `L` and `SL` that the tracer's filter never sees.
//!
//! Invariants: a filter is biased by design (it removes light), is off by default and is refused
//! by every method but `pt` and `pt-cf`; classes longer than [`MAX_TOKENS`] tokens match `*`
//! patterns only.

use crate::math::Rgb;

/// Tokens a class records exactly (2 bits each in a `u64`).
pub const MAX_TOKENS: u32 = 31;

const D: u64 = 1;
const S: u64 = 2;
const L: u64 = 3;

/// A path's class so far: its tokens, 2 bits each, the first in the lowest bits.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PathClass {
    bits: u64,
    len: u32,
}

impl PathClass {
    /// Appends a vertex: `D` for a non-Dirac one; a Dirac one adds `S` unless the last token is `S`.
    #[inline]
    pub fn push(&mut self, dirac: bool) {
        let t = if dirac { S } else { D };
        if t == S && self.len > 0 && self.len <= MAX_TOKENS && self.token(self.len - 1) == S {
            return;
        }
        self.append(t);
    }

    /// The class of a contribution that reaches the light from here (`… L`).
    #[inline]
    pub fn lit(mut self) -> Self {
        self.append(L);
        self
    }

    /// Appends token `t` (recorded only within the first [`MAX_TOKENS`]; the length counts on).
    #[inline]
    fn append(&mut self, t: u64) {
        if self.len < MAX_TOKENS {
            self.bits |= t << (2 * self.len);
        }
        self.len = self.len.saturating_add(1);
    }

    fn token(&self, i: u32) -> u64 {
        (self.bits >> (2 * i)) & 3
    }
}

/// A parsed `--path-filter`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PathFilter {
    patterns: Vec<(PathClass, bool)>,
}

impl PathFilter {
    /// Parses `DL,DS*,…`; the error names the pattern and the character.
    pub fn parse(s: &str) -> Result<Self, String> {
        s.split(',')
            .map(str::trim)
            .map(|p| parse_pattern(p, s))
            .collect::<Result<_, _>>()
            .map(|patterns| PathFilter { patterns })
    }

    /// True when a contribution of class `c` (ending in `L`) passes.
    #[inline]
    pub fn keeps(&self, c: PathClass) -> bool {
        self.patterns.iter().any(|&(p, prefix)| {
            if prefix {
                p.len <= c.len.min(MAX_TOKENS) && (c.bits ^ p.bits) & ((1u64 << (2 * p.len)) - 1) == 0
            } else {
                c.len <= MAX_TOKENS && p == c
            }
        })
    }
}

/// One pattern `p` of the list `all`: its class and whether it is a prefix.
fn parse_pattern(p: &str, all: &str) -> Result<(PathClass, bool), String> {
    let (body, prefix) = p.strip_suffix('*').map_or((p, false), |b| (b, true));
    if body.is_empty() && !prefix {
        return Err(format!("empty pattern in `{all}` (classes are made of D, S, L; `*` ends a prefix)"));
    }
    let tokens = body
        .chars()
        .map(|ch| match ch.to_ascii_uppercase() {
            'D' => Ok(D),
            'S' => Ok(S),
            'L' => Ok(L),
            _ => Err(format!("pattern `{p}`: `{ch}` is not D, S or L (a trailing `*` makes a prefix)")),
        })
        .collect::<Result<Vec<u64>, String>>()?;
    if tokens.len() > MAX_TOKENS as usize {
        return Err(format!("pattern `{p}` is longer than {MAX_TOKENS} tokens"));
    }
    if tokens.iter().rev().skip(usize::from(!prefix)).any(|&t| t == L) {
        return Err(format!("pattern `{p}`: L (the light) can only end a class"));
    }
    if tokens.windows(2).any(|w| w == [S, S]) {
        return Err(format!("pattern `{p}`: SS never occurs (a Dirac chain is one S)"));
    }
    if !prefix && tokens.last() != Some(&L) {
        return Err(format!("pattern `{p}` never matches: a class ends in L (did you mean `{p}L` or `{p}*`?)"));
    }
    let mut c = PathClass::default();
    tokens.into_iter().for_each(|t| c.append(t));
    Ok((c, prefix))
}

/// `v` if `filter` (none: every class) keeps a contribution reaching the light from `class`, else 0.
#[inline]
pub fn kept(filter: Option<&PathFilter>, class: PathClass, v: Rgb) -> Rgb {
    if filter.is_none_or(|f| f.keeps(class.lit())) {
        v
    } else {
        Rgb::ZERO
    }
}

/// `--path-filter`'s value parser: the text, once it parses.
pub fn check_filter(s: &str) -> Result<String, String> {
    PathFilter::parse(s).map(|_| s.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn class(s: &str) -> PathClass {
        let mut c = PathClass::default();
        for ch in s.trim_end_matches('L').chars() {
            c.push(ch == 'S');
        }
        c.lit()
    }

    #[test]
    fn dirac_runs_are_one_token_and_patterns_match() {
        let mut c = PathClass::default();
        for dirac in [false, true, true, true, false] {
            c.push(dirac);
        }
        assert_eq!(c.lit(), class("DSDL"));
        let f = PathFilter::parse("DSL, DD*").unwrap();
        assert!(f.keeps(class("DSL")) && f.keeps(class("DDL")) && f.keeps(class("DDSDL")));
        assert!(!f.keeps(class("DL")) && !f.keeps(class("SDSL")) && !f.keeps(class("DSDL")));
        // every class matches exactly one of L, S*, D*
        let part = ["L", "S*", "D*"].map(|p| PathFilter::parse(p).unwrap());
        for k in ["L", "SL", "DL", "SDSL", "DDDDSL", "SDDL"] {
            assert_eq!(part.iter().filter(|f| f.keeps(class(k))).count(), 1, "{k}");
        }
    }

    #[test]
    fn the_token_limit_is_exact() {
        let long: String = "DS".repeat(15) + "L"; // 31 tokens
        assert!(PathFilter::parse(&long).unwrap().keeps(class(&long)));
        assert!(PathFilter::parse(&("D".to_string() + &long)).unwrap_err().contains("longer than 31"));
        let f = PathFilter::parse(" dd* , l ").unwrap(); // spaces around patterns, lower case
        assert!(f.keeps(class("L")) && f.keeps(class("DDSL")) && !f.keeps(class("DSL")));
    }

    #[test]
    fn long_classes_match_prefixes_only() {
        let mut c = PathClass::default();
        for i in 0..40 {
            c.push(i % 2 == 1);
        }
        let c = c.lit();
        assert!(PathFilter::parse("DSDS*").unwrap().keeps(c));
        assert!(PathFilter::parse("*").unwrap().keeps(c));
        assert!(!PathFilter::parse("DL").unwrap().keeps(c));
    }

    #[test]
    fn bad_patterns_are_named() {
        for (p, what) in [
            ("DX", "`X`"),
            ("LD", "L (the light)"),
            ("DSSL", "SS"),
            ("DL,", "empty pattern"),
            ("DS", "did you mean `DSL` or `DS*`"),
            ("Lé", "`é`"),
            ("DL*", "L (the light)"),
        ] {
            let e = PathFilter::parse(p).unwrap_err();
            assert!(e.contains(what), "{p}: {e}");
        }
    }
}
