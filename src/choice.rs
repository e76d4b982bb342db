//! Closed sets of named options (samplers, strategies, solvers, integrators): each enum lists its
//! values with the name scene files and the command line use and a one-line description, and
//! gets `FromStr` (with a nearest-name hint) and `Display` from that one list, so no other layer
//! mirrors it.

/// An enum whose values have names (see the module docs). Implement it with [`crate::choices!`].
pub trait Choice: Copy + PartialEq + Sized + 'static {
    /// Every value, with its name and a one-line description, in documentation order.
    const CHOICES: &'static [(Self, &'static str, &'static str)];

    /// What the set is called in messages ("sampler", "integrator", …).
    const WHAT: &'static str;

    /// The value's name.
    fn name(self) -> &'static str {
        Self::CHOICES.iter().find(|c| c.0 == self).map_or("?", |c| c.1)
    }

    /// Every name, in order.
    fn names() -> Vec<&'static str> {
        Self::CHOICES.iter().map(|c| c.1).collect()
    }

    /// The value named `s`, or an error listing the names (and the nearest one).
    fn parse_name(s: &str) -> Result<Self, String> {
        // '_' and '-' are the same letter in names (scene files write gauss_seidel, the
        // command line gauss-seidel).
        let norm = |n: &str| n.replace('_', "-");
        if let Some(c) = Self::CHOICES.iter().find(|c| norm(c.1) == norm(s)) {
            return Ok(c.0);
        }
        let names = Self::names();
        let hint = nearest(s, names.iter().copied()).map(|n| format!("; the nearest is '{n}'")).unwrap_or_default();
        Err(format!("unknown {} '{s}' (expected one of: {}{hint})", Self::WHAT, names.join(", ")))
    }
}

/// The candidate closest to `name` by (case-insensitive) edit distance, if it is close: at most
/// half the longer name's length, and at least 2 edits allowed. For "did you mean" hints.
pub fn nearest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    candidates
        .into_iter()
        .map(|c| (edit_distance(name, c), c))
        .min()
        .filter(|&(d, c)| d <= (c.len().max(name.len()) / 2).max(2))
        .map(|(_, c)| c)
}

/// Levenshtein distance (case-insensitive).
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.to_lowercase().chars().collect(), b.to_lowercase().chars().collect());
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != cb)).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// Implements [`Choice`], `FromStr` and `Display` for an enum from its list of
/// `Variant => "name", "description"` entries.
#[macro_export]
macro_rules! choices {
    ($ty:ty, $what:literal, { $($variant:expr => $name:literal, $help:literal;)+ }) => {
        impl $crate::choice::Choice for $ty {
            const CHOICES: &'static [(Self, &'static str, &'static str)] = &[$(($variant, $name, $help)),+];
            const WHAT: &'static str = $what;
        }
        impl ::std::str::FromStr for $ty {
            type Err = String;
            fn from_str(s: &str) -> ::std::result::Result<Self, String> {
                <$ty as $crate::choice::Choice>::parse_name(s)
            }
        }
        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str($crate::choice::Choice::name(*self))
            }
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Fruit {
        Apple,
        Pear,
    }
    crate::choices!(Fruit, "fruit", { Fruit::Apple => "apple", "red"; Fruit::Pear => "pear", "green"; });

    #[test]
    fn names_parse_print_and_hint() {
        assert_eq!("pear".parse::<Fruit>().unwrap(), Fruit::Pear);
        assert_eq!(Fruit::Apple.to_string(), "apple");
        let e = "aple".parse::<Fruit>().unwrap_err();
        assert!(
            e.contains("unknown fruit 'aple'") && e.contains("apple, pear") && e.contains("nearest is 'apple'"),
            "{e}"
        );
        assert!(!"banana".parse::<Fruit>().unwrap_err().contains("nearest"));
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("Diffuse", "diffuse"), 0, "case-insensitive");
    }
}
