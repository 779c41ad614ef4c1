//! Helpers shared by the text readers: encodings, lines, numbers.
//!
//! Lines are read one at a time and are at most [`MAX_LINE`] bytes (1 MiB): a longer line is
//! refused, naming the file and the line, before more of it is held. No mesh statement comes
//! near it (an OBJ face of 10,000 corners is about 100 KB); a file with such a line is not a
//! text mesh, or is damaged (a binary file read as text, a file without line ends).

use super::error::{IoError, Location, ProblemKind};
use std::borrow::Cow;
use std::io::BufRead;
use std::path::Path;

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

/// `bytes` decoded (see [`decode`]); an encoding problem is an error naming `path`.
pub fn decode_file<'a>(
    path: &Path,
    format: &'static str,
    bytes: &'a [u8],
) -> Result<Cow<'a, [u8]>, IoError> {
    decode(bytes).map_err(|reason| {
        super::error::malformed(
            path,
            format,
            Location::File,
            ProblemKind::Encoding { reason },
        )
    })
}

/// The longest line the text readers take, bytes (1 MiB, line end excluded).
pub const MAX_LINE: usize = 1 << 20;

/// Why the next line could not be read.
#[derive(Debug)]
pub enum LineError {
    /// The reader failed.
    Io(std::io::Error),
    /// Line `line` is longer than [`MAX_LINE`] bytes.
    TooLong { line: u64 },
}

/// Turns a failure to read a line of `path` (a `format` file) into its [`IoError`]: a read
/// error, or a line too long (a malformed file, naming the line).
pub fn line_error<'a>(
    path: &'a Path,
    format: &'static str,
) -> impl Fn(LineError) -> IoError + Copy + 'a {
    move |e| match e {
        LineError::Io(source) => IoError::Read {
            path: path.to_path_buf(),
            source,
        },
        LineError::TooLong { line } => super::error::malformed(
            path,
            format,
            Location::Line(line),
            ProblemKind::LineTooLong { limit: MAX_LINE },
        ),
    }
}

/// Lines read one at a time from a [`BufRead`], with their 1-based numbers and the line end
/// (`\n`, `\r\n` or a lone `\r`) removed. Only the current line is held, and at most
/// [`MAX_LINE`] bytes of it: memory is bounded whatever the file.
pub struct LineReader<R> {
    inner: R,
    line: Vec<u8>,
    number: u64,
    /// The last line ended in `\r`: a `\n` right after it belongs to that line end.
    after_cr: bool,
}

impl<R: BufRead> LineReader<R> {
    /// Lines of `inner`, from its current position.
    pub fn new(inner: R) -> LineReader<R> {
        LineReader {
            inner,
            line: Vec::new(),
            number: 0,
            after_cr: false,
        }
    }

    /// The next line and its number; `None` at the end; an error when the line is longer than
    /// [`MAX_LINE`] bytes (nothing past the limit is kept).
    pub fn next_line(&mut self) -> Result<Option<(u64, &[u8])>, LineError> {
        self.next_line_within(MAX_LINE)
    }

    /// [`LineReader::next_line`] with a limit of `limit` bytes.
    fn next_line_within(&mut self, limit: usize) -> Result<Option<(u64, &[u8])>, LineError> {
        self.line.clear();
        let io = LineError::Io;
        if std::mem::take(&mut self.after_cr)
            && self.inner.fill_buf().map_err(io)?.first() == Some(&b'\n')
        {
            self.inner.consume(1);
        }
        if self.inner.fill_buf().map_err(io)?.is_empty() {
            return Ok(None);
        }
        self.number += 1;
        loop {
            let chunk = self.inner.fill_buf().map_err(io)?;
            if chunk.is_empty() {
                break;
            }
            let end = chunk.iter().position(|&b| b == b'\n' || b == b'\r');
            let take = end.unwrap_or(chunk.len());
            if self.line.len() + take > limit {
                return Err(LineError::TooLong { line: self.number });
            }
            self.line.extend_from_slice(&chunk[..take]);
            match end {
                Some(i) => {
                    self.after_cr = chunk[i] == b'\r';
                    self.inner.consume(i + 1);
                    break;
                }
                None => self.inner.consume(take),
            }
        }
        Ok(Some((self.number, &self.line)))
    }

    /// Bytes held for the current line (its buffer's capacity).
    #[cfg(test)]
    pub fn held(&self) -> usize {
        self.line.capacity()
    }
}

/// The lines of `text` (see [`LineReader`]), for callers that have the bytes in memory.
pub fn lines(text: &[u8]) -> impl Iterator<Item = (u64, Vec<u8>)> + '_ {
    let mut r = LineReader::new(text);
    std::iter::from_fn(move || match r.next_line() {
        Ok(Some((n, l))) => Some((n, l.to_vec())),
        _ => None,
    })
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

/// The largest coordinate magnitude a mesh may have: beyond it the mesh's volumes (cubes of
/// its lengths, summed over its faces) overflow double precision and its reports would hold
/// infinities.
pub const COORDINATE_MAX: f64 = 1e100;

/// Parses a coordinate: a finite `f64` ([`number`]) of magnitude at most [`COORDINATE_MAX`].
#[inline]
pub fn coordinate(token: &[u8]) -> Result<f64, ProblemKind> {
    let v = number(token)?;
    within(v)
}

/// `v` when its magnitude is at most [`COORDINATE_MAX`].
#[inline]
pub fn within(v: f64) -> Result<f64, ProblemKind> {
    if v.abs() > COORDINATE_MAX {
        return Err(ProblemKind::TooLarge {
            value: v,
            max: COORDINATE_MAX,
        });
    }
    Ok(v)
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
        assert_eq!(coordinate(b"-1e100"), Ok(-1e100));
        assert!(matches!(
            coordinate(b"1.1e100"),
            Err(ProblemKind::TooLarge { .. })
        ));
        assert!(matches!(
            coordinate(b"-1e308"),
            Err(ProblemKind::TooLarge { .. })
        ));
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
        assert_eq!(l, vec![(1, b"v 1 2 3".to_vec()), (2, b"f 1".to_vec())]);
        let old_mac: Vec<_> = lines(b"a\rb\r").collect();
        assert_eq!(old_mac.len(), 2);
        let mixed: Vec<_> = lines(b"\na\r\n\rb").map(|(_, l)| l).collect();
        assert_eq!(
            mixed,
            vec![b"".to_vec(), b"a".to_vec(), b"".to_vec(), b"b".to_vec()]
        );
        assert_eq!(lines(b"").count(), 0);
    }

    /// An endless line, handed out in 8 KiB pieces, counting what it handed out.
    struct Endless {
        piece: Vec<u8>,
        given: usize,
    }

    impl std::io::Read for Endless {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = buf.len().min(self.piece.len());
            buf[..n].copy_from_slice(&self.piece[..n]);
            self.given += n;
            Ok(n)
        }
    }

    impl std::io::BufRead for Endless {
        fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
            Ok(&self.piece)
        }
        fn consume(&mut self, n: usize) {
            self.given += n;
        }
    }

    #[test]
    fn hostile_endless_line_is_refused_at_the_limit() {
        let mut r = LineReader::new(Endless {
            piece: vec![b'7'; 8192],
            given: 0,
        });
        match r.next_line() {
            Err(LineError::TooLong { line: 1 }) => {}
            other => panic!("{:?}", other.map(|l| l.map(|(n, b)| (n, b.len())))),
        }
        // Nothing past the limit was held or read.
        assert!(r.held() <= MAX_LINE, "held {}", r.held());
        assert!(r.inner.given <= MAX_LINE, "read {}", r.inner.given);
    }

    #[test]
    fn lines_up_to_the_limit_are_read_and_the_next_longer_one_is_named() {
        // Lines of the limit's length and one byte more, with every kind of line end, read
        // through a small buffer (the line arrives in pieces).
        let limit = 100;
        let ok = "x".repeat(limit);
        for end in ["\n", "\r\n", "\r"] {
            let text = format!("a{end}{ok}{end}{ok}x{end}b{end}");
            let mut r = LineReader::new(std::io::BufReader::with_capacity(7, text.as_bytes()));
            assert_eq!(r.next_line_within(limit).unwrap(), Some((1, &b"a"[..])));
            assert_eq!(r.next_line_within(limit).unwrap(), Some((2, ok.as_bytes())));
            assert!(matches!(
                r.next_line_within(limit),
                Err(LineError::TooLong { line: 3 })
            ));
        }
    }

    /// A reader that hands out a million blank lines a few bytes at a time, and what the
    /// line reader holds meanwhile: one line, not the million.
    #[test]
    fn hostile_million_blank_lines_hold_one_line() {
        let text = "\n".repeat(1_000_000) + "v 1 2 3\n";
        let mut r = LineReader::new(std::io::BufReader::with_capacity(16, text.as_bytes()));
        let (mut count, mut most) = (0, 0);
        while let Some((n, _)) = r.next_line().unwrap() {
            count = n;
            most = most.max(r.held());
        }
        assert_eq!(count, 1_000_001);
        assert!(most <= 64, "held {most} bytes");
    }
}
