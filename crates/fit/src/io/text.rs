//! Text as instruments write it: UTF-8 or UTF-16 with or without a byte-order mark (or
//! Latin-1), any line ending, numbers separated by whitespace, tabs, `,` or `;`, with a
//! decimal point or a decimal comma.

use std::borrow::Cow;

/// Decode a text file: BOM-marked UTF-8/UTF-16, UTF-16 recognised by its zero bytes,
/// then UTF-8, then Latin-1 (never fails).
pub fn decode(bytes: &[u8]) -> Cow<'_, str> {
    if let Some(rest) = bytes.strip_prefix(b"\xef\xbb\xbf") {
        return String::from_utf8_lossy(rest);
    }
    if let Some(rest) = bytes.strip_prefix(b"\xff\xfe") {
        return Cow::Owned(utf16(rest, true));
    }
    if let Some(rest) = bytes.strip_prefix(b"\xfe\xff") {
        return Cow::Owned(utf16(rest, false));
    }
    let head = &bytes[..bytes.len().min(256) & !1];
    if head.len() >= 4 {
        let zeros_odd = head.iter().skip(1).step_by(2).filter(|&&b| b == 0).count();
        let zeros_even = head.iter().step_by(2).filter(|&&b| b == 0).count();
        let half = head.len() / 2;
        if zeros_odd * 10 >= half * 9 && zeros_even == 0 {
            return Cow::Owned(utf16(bytes, true));
        }
        if zeros_even * 10 >= half * 9 && zeros_odd == 0 {
            return Cow::Owned(utf16(bytes, false));
        }
    }
    match std::str::from_utf8(bytes) {
        Ok(s) => Cow::Borrowed(s),
        Err(e) if e.valid_up_to() + 4 >= bytes.len() => {
            // A file cut in the middle of a multi-byte character.
            String::from_utf8_lossy(bytes)
        }
        Err(_) => Cow::Owned(bytes.iter().map(|&b| b as char).collect()),
    }
}

fn utf16(bytes: &[u8], little: bool) -> String {
    let units: Vec<u16> = bytes
        .chunks_exact(2)
        .map(|c| {
            if little {
                u16::from_le_bytes([c[0], c[1]])
            } else {
                u16::from_be_bytes([c[0], c[1]])
            }
        })
        .collect();
    String::from_utf16_lossy(&units)
}

/// What a content check of a text format reads: the first 16 kB decoded, or `None` when
/// the file does not look like text.
pub(crate) fn sniff_sample(bytes: &[u8]) -> Option<Cow<'_, str>> {
    looks_like_text(bytes).then(|| decode(&bytes[..bytes.len().min(SNIFF_LEN)]))
}

/// Bytes of a file that [`sniff_sample`] reads.
pub(crate) const SNIFF_LEN: usize = 16384;

/// The first 200 lines of a [`sniff_sample`] without the last one, which the cut may have
/// split (a single line is kept).
pub(crate) fn sample_lines(sample: &str) -> Vec<&str> {
    let mut lines: Vec<&str> = sample.lines().take(200).collect();
    lines.truncate(lines.len().saturating_sub(1).max(1));
    lines
}

/// True when the bytes look like text (few control characters in the first kB).
pub fn looks_like_text(bytes: &[u8]) -> bool {
    let t = decode(&bytes[..bytes.len().min(2048)]);
    let n = t.chars().count().max(1);
    let bad = t
        .chars()
        .filter(|c| c.is_control() && !matches!(c, '\n' | '\r' | '\t' | '\u{c}'))
        .count();
    bad * 50 < n
}

/// Field separator of a numeric table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sep {
    /// Runs of spaces/tabs (also accepts a comma or semicolon between fields).
    Whitespace,
    /// Tab.
    Tab,
    /// Comma.
    Comma,
    /// Semicolon.
    Semicolon,
}

/// How the numbers of a table are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dialect {
    /// Separator between fields.
    pub sep: Sep,
    /// `1,5` means 1.5.
    pub decimal_comma: bool,
}

impl Dialect {
    /// Guess from sample lines of data: a semicolon-separated table or whitespace-separated
    /// fields with single commas inside them use a decimal comma.
    pub fn guess<'a>(lines: impl Iterator<Item = &'a str>) -> Dialect {
        let (mut semi, mut tab, mut comma, mut ws_multi, mut comma_inside, mut n) =
            (0, 0, 0, 0, 0, 0);
        for l in lines.take(50) {
            let l = l.trim();
            if l.is_empty() {
                continue;
            }
            n += 1;
            if l.contains(';') {
                semi += 1;
            }
            if l.contains('\t') {
                tab += 1;
            }
            if l.contains(',') {
                comma += 1;
            }
            let toks: Vec<&str> = l.split_whitespace().collect();
            if toks.len() >= 2 {
                ws_multi += 1;
                if toks.iter().any(|t| {
                    t.matches(',').count() == 1 && !t.ends_with(',') && !t.starts_with(',')
                }) && toks.iter().all(|t| t.matches(',').count() <= 1)
                {
                    comma_inside += 1;
                }
            }
        }
        if n == 0 {
            return Dialect {
                sep: Sep::Whitespace,
                decimal_comma: false,
            };
        }
        if semi * 2 >= n {
            return Dialect {
                sep: Sep::Semicolon,
                decimal_comma: comma > 0,
            };
        }
        if tab * 2 >= n && comma_inside * 2 >= n {
            return Dialect {
                sep: Sep::Tab,
                decimal_comma: true,
            };
        }
        if ws_multi * 2 >= n && comma_inside * 2 >= n {
            return Dialect {
                sep: Sep::Whitespace,
                decimal_comma: true,
            };
        }
        if comma * 2 >= n {
            return Dialect {
                sep: Sep::Comma,
                decimal_comma: false,
            };
        }
        Dialect {
            sep: if tab * 2 >= n {
                Sep::Tab
            } else {
                Sep::Whitespace
            },
            decimal_comma: false,
        }
    }

    /// Split a line into fields (empty fields kept for comma/semicolon/tab tables).
    pub fn fields<'a>(&self, line: &'a str) -> Vec<&'a str> {
        let line = line.trim_matches(|c: char| c == '\r' || c == '\n' || c == ' ');
        match self.sep {
            Sep::Whitespace if self.decimal_comma => line.split_whitespace().collect(),
            Sep::Whitespace => line
                .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
                .filter(|t| !t.is_empty())
                .collect(),
            Sep::Tab => line.split('\t').map(str::trim).collect(),
            Sep::Comma => line.split(',').map(str::trim).collect(),
            Sep::Semicolon => line.split(';').map(str::trim).collect(),
        }
    }

    /// Parse one field; words for missing data (`nan`, `bad`, `inf`, `-`, ``) give NaN.
    pub fn number(&self, field: &str) -> Option<f64> {
        let f = field.trim().trim_matches('"');
        let owned;
        let f = if self.decimal_comma && f.contains(',') {
            owned = f.replace(',', ".");
            owned.as_str()
        } else {
            f
        };
        if let Ok(v) = f.parse::<f64>() {
            return Some(if v.is_finite() { v } else { f64::NAN });
        }
        match f.to_ascii_lowercase().as_str() {
            "nan" | "bad" | "inf" | "-inf" | "+inf" | "infinite" | "invalid" | "void"
            | "novalue" | "no value" | "---" => Some(f64::NAN),
            _ => None,
        }
    }

    /// Parse a whole row; `None` if any non-empty field is not a number. Trailing empty
    /// fields (`1,2,`) are dropped; inner empty fields are NaN.
    pub fn row(&self, line: &str) -> Option<Vec<f64>> {
        let mut f = self.fields(line);
        while f.last().is_some_and(|s| s.is_empty()) {
            f.pop();
        }
        if f.is_empty() {
            return None;
        }
        f.iter()
            .map(|s| {
                if s.is_empty() {
                    Some(f64::NAN)
                } else {
                    self.number(s)
                }
            })
            .collect()
    }
}

/// Parse one row of numbers separated by whitespace, commas, semicolons or tabs.
/// Empty fields (as in `1.0,2.0,,`) are skipped. Non-finite values become NaN.
/// Returns `None` if any field is not a number.
pub fn parse_row(line: &str) -> Option<Vec<f64>> {
    let mut out = Vec::new();
    for tok in line.split(|c: char| c.is_whitespace() || c == ',' || c == ';') {
        if tok.is_empty() {
            continue;
        }
        let v: f64 = tok.parse().ok()?;
        out.push(if v.is_finite() { v } else { f64::NAN });
    }
    (!out.is_empty()).then_some(out)
}

/// Split a header line into key and value at the first `=` or `:` (after an optional
/// leading `#`, `%`, `;` or `//`). Returns `None` for lines that are not `key sep value`.
pub fn key_value(line: &str) -> Option<(String, String)> {
    let l = line
        .trim()
        .trim_start_matches(['#', '%', ';', '*'])
        .trim_start_matches("//")
        .trim();
    let i = l.find(['=', ':'])?;
    let (k, v) = (l[..i].trim(), l[i + 1..].trim());
    if k.is_empty() || k.len() > 80 {
        return None;
    }
    Some((k.to_string(), v.to_string()))
}

/// The refusal of a text export whose last number was cut short: a file that does not end
/// with a line break and whose last field ends where no number can (`16.`, `1.5e`, `-`),
/// as a copy or export interrupted inside `16.58112` leaves it. A number cut after a digit
/// cannot be told from a whole one; this catches the cuts that can.
pub(crate) fn check_not_cut(ctx: super::Ctx<'_>, text: &str) -> Result<(), crate::ReadError> {
    let t = text.trim_end_matches(['\0', ' ', '\t']);
    if t.is_empty() || t.ends_with(['\n', '\r']) {
        return Ok(());
    }
    let line = t.lines().count();
    let last = t
        .rsplit(|c: char| c.is_whitespace() || matches!(c, ',' | ';'))
        .next()
        .unwrap_or("");
    let cut = last.ends_with(['.', 'e', 'E', '+', '-']) && last.bytes().any(|b| b.is_ascii_digit());
    if cut {
        return Err(ctx.err(
            &format!("line {line}"),
            format!("the file ends inside a number (`{last}`): it was cut short"),
            "the export or copy was interrupted; re-export or re-copy the file",
        ));
    }
    Ok(())
}
