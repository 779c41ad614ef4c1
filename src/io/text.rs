//! Helpers shared by the text readers: encodings, lines, numbers.

use super::error::ProblemKind;
use std::borrow::Cow;

/// The text as UTF-8 bytes: a UTF-8 byte-order mark is dropped, UTF-16 (with a byte-order mark,
/// or recognised by its zero bytes) is transcoded. Other bytes pass through untouched: tokens
/// are ASCII, and comments may be in any encoding.
pub fn decode(bytes: &[u8]) -> Result<Cow<'_, [u8]>, String> {
    let utf16 = |le: bool, body: &[u8]| -> Result<Cow<'_, [u8]>, String> {
        if !body.len().is_multiple_of(2) {
            return Err("UTF-16 text with an odd number of bytes".into());
        }
        let units = body.chunks_exact(2).map(|c| {
            if le {
                u16::from_le_bytes([c[0], c[1]])
            } else {
                u16::from_be_bytes([c[0], c[1]])
            }
        });
        let s: String = char::decode_utf16(units)
            .collect::<Result<String, _>>()
            .map_err(|e| format!("invalid UTF-16 text: {e}"))?;
        Ok(Cow::Owned(s.into_bytes()))
    };
    match bytes {
        [0xEF, 0xBB, 0xBF, rest @ ..] => Ok(Cow::Borrowed(rest)),
        [0xFE, 0xFF, rest @ ..] => utf16(false, rest),
        [0xFF, 0xFE, rest @ ..] => utf16(true, rest),
        [0, a, ..] if *a != 0 => utf16(false, bytes),
        [a, 0, ..] if *a != 0 => utf16(true, bytes),
        _ => Ok(Cow::Borrowed(bytes)),
    }
}

/// Lines with their 1-based numbers, line ends (`\n`, `\r\n`, lone `\r`) removed.
pub fn lines(text: &[u8]) -> impl Iterator<Item = (u64, &[u8])> {
    let cr_only = !text.contains(&b'\n') && text.contains(&b'\r');
    let sep = if cr_only { b'\r' } else { b'\n' };
    let mut parts: Vec<&[u8]> = text.split(move |&b| b == sep).collect();
    if parts.last().is_some_and(|l| l.is_empty()) {
        parts.pop();
    }
    parts
        .into_iter()
        .enumerate()
        .map(|(i, l)| (i as u64 + 1, l.strip_suffix(b"\r").unwrap_or(l)))
}

/// Parses a finite `f64` (`1.5e-3`, `-0.`, `+2`, `.5` are fine; NaN and infinity are not).
#[inline]
pub fn number(token: &[u8]) -> Result<f64, ProblemKind> {
    let s = std::str::from_utf8(token).map_err(|_| ProblemKind::NotANumber {
        token: String::from_utf8_lossy(token).into_owned(),
    })?;
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ProblemKind::NonFinite {
            token: s.to_string(),
        }),
        Err(_) => Err(ProblemKind::NotANumber {
            token: s.to_string(),
        }),
    }
}

/// Splits on ASCII whitespace.
#[inline]
pub fn words(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| b.is_ascii_whitespace())
        .filter(|w| !w.is_empty())
}

/// Lossy text of a token, for messages (at most 40 characters).
pub fn show(token: &[u8]) -> String {
    let s = String::from_utf8_lossy(token);
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        for (s, v) in [
            ("1.5e-3", 1.5e-3),
            ("-0.", 0.0),
            ("+2", 2.0),
            (".5", 0.5),
            ("2.e1", 20.0),
        ] {
            assert_eq!(number(s.as_bytes()), Ok(v));
        }
        assert!(matches!(number(b"nan"), Err(ProblemKind::NonFinite { .. })));
        assert!(matches!(
            number(b"-inf"),
            Err(ProblemKind::NonFinite { .. })
        ));
        assert!(matches!(
            number(b"3.1+e2"),
            Err(ProblemKind::NotANumber { .. })
        ));
    }

    #[test]
    fn utf16_and_line_ends() {
        let mut b = vec![0xFE, 0xFF];
        for c in "v 1 2 3\r\nf 1\r\n".encode_utf16() {
            b.extend_from_slice(&c.to_be_bytes());
        }
        let t = decode(&b).unwrap();
        let l: Vec<_> = lines(&t).collect();
        assert_eq!(l, vec![(1, &b"v 1 2 3"[..]), (2, &b"f 1"[..])]);
        let old_mac: Vec<_> = lines(b"a\rb\r").collect();
        assert_eq!(old_mac.len(), 2);
    }
}
