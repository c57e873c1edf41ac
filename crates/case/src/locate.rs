//! Where a problem is in the user's text: byte spans of the text as
//! checked (after `--set`, and after keys with problems were taken out)
//! mapped back to `file:line:col` of the user's file, or to the `--set`
//! that wrote the line.

use std::ops::Range;

/// Turns byte spans in the final text into `file:line:col` of the user's file
/// (or `--set ...` for lines that `--set` changed).
pub(crate) struct Locator<'a> {
    file: &'a str,
    source: &'a str,
    sets: &'a [String],
    /// For each line of the final text (0-based), the line of the original
    /// file it is (0-based), or `None` if `--set` changed or added it.
    map: Vec<Option<usize>>,
}

impl<'a> Locator<'a> {
    /// `changed`: the text differs from the user's file other than by
    /// `sets` (keys removed after a schema problem), so lines are aligned by
    /// a diff even without `--set`.
    pub(crate) fn new(
        file: &'a str,
        original: &str,
        source: &'a str,
        sets: &'a [String],
        changed: bool,
    ) -> Self {
        let a: Vec<&str> = original.lines().collect();
        let b: Vec<&str> = source.lines().collect();
        let map = if (sets.is_empty() && !changed) || a.len().saturating_mul(b.len()) > 16_000_000 {
            (0..b.len()).map(Some).collect()
        } else {
            diff_lines(&a, &b)
        };
        Locator {
            file,
            source,
            sets,
            map,
        }
    }

    /// Whether the line of `span` was changed or added by `--set`.
    pub(crate) fn set_by_override(&self, span: &Range<usize>) -> bool {
        let (line, _) = line_col(self.source, span.start);
        self.map.get(line - 1).copied().flatten().is_none()
    }

    pub(crate) fn at(&self, span: Option<Range<usize>>) -> String {
        let Some(span) = span else {
            return self.file.to_string();
        };
        let (line, col) = line_col(self.source, span.start);
        match self.map.get(line - 1).copied().flatten() {
            Some(orig) => format!("{}:{}:{col}", self.file, orig + 1),
            None => {
                // The line came from --set: name the override(s) on it.
                let text = self.source.lines().nth(line - 1).unwrap_or("");
                let on_line: Vec<&String> = self
                    .sets
                    .iter()
                    .filter(|s| {
                        let leaf = s
                            .split('=')
                            .next()
                            .unwrap_or("")
                            .rsplit('.')
                            .next()
                            .unwrap_or("")
                            .trim();
                        !leaf.is_empty() && text.contains(leaf)
                    })
                    .collect();
                // No override on the line (a key missing from a file
                // with no such line, e.g. an empty one): the file.
                if on_line.is_empty() {
                    return self.file.to_string();
                }
                let which: Vec<&str> = on_line.iter().map(|s| s.as_str()).collect();
                format!("--set {} (in {})", which.join(" --set "), self.file)
            }
        }
    }
}

/// 1-based line and column (in characters) of byte offset `pos`.
pub(crate) fn line_col(text: &str, pos: usize) -> (usize, usize) {
    let pos = pos.min(text.len());
    let before = &text[..text.floor_char_boundary_compat(pos)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
    (line, col)
}

trait FloorCharBoundary {
    fn floor_char_boundary_compat(&self, i: usize) -> usize;
}
impl FloorCharBoundary for str {
    fn floor_char_boundary_compat(&self, mut i: usize) -> usize {
        while i > 0 && !self.is_char_boundary(i) {
            i -= 1;
        }
        i
    }
}

/// Longest-common-subsequence alignment of lines: for each line of `b`, the
/// index of the equal line of `a` it is matched with, if any.
fn diff_lines(a: &[&str], b: &[&str]) -> Vec<Option<usize>> {
    let (n, m) = (a.len(), b.len());
    // lcs[i][j] = LCS length of a[i..], b[j..].
    let mut lcs = vec![0u32; (n + 1) * (m + 1)];
    let w = m + 1;
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i * w + j] = if a[i] == b[j] {
                lcs[(i + 1) * w + j + 1] + 1
            } else {
                lcs[(i + 1) * w + j].max(lcs[i * w + j + 1])
            };
        }
    }
    let mut map = vec![None; m];
    let (mut i, mut j) = (0, 0);
    while i < n && j < m {
        if a[i] == b[j] {
            map[j] = Some(i);
            i += 1;
            j += 1;
        } else if lcs[(i + 1) * w + j] >= lcs[i * w + j + 1] {
            i += 1;
        } else {
            j += 1;
        }
    }
    map
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diff_maps_unchanged_lines() {
        let a = ["a", "b", "c", "d"];
        let b = ["a", "b2", "b", "c", "x", "d"];
        assert_eq!(
            diff_lines(&a, &b),
            vec![Some(0), None, Some(1), Some(2), None, Some(3)]
        );
    }
}
