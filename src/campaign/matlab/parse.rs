//! Byte-level reading of level-5 data elements (MathWorks "MAT-File Format", chapter 1).
//!
//! Every read is bounds-checked against the enclosing element; every count taken from the
//! file is checked against the bytes that remain before anything is allocated; nesting is
//! limited to [`MAX_DEPTH`]; compressed elements are inflated only at the top level (as
//! MATLAB writes them) and within the file's inflated-bytes budget.

use super::header::HEADER_LEN;
use super::{MatError, MatValue};
use std::io::Read;

/// Element data types (table 1-1).
pub(super) const MI_INT8: u32 = 1;
pub(super) const MI_UINT8: u32 = 2;
pub(super) const MI_INT16: u32 = 3;
pub(super) const MI_UINT16: u32 = 4;
pub(super) const MI_INT32: u32 = 5;
pub(super) const MI_UINT32: u32 = 6;
pub(super) const MI_SINGLE: u32 = 7;
pub(super) const MI_DOUBLE: u32 = 9;
pub(super) const MI_INT64: u32 = 12;
pub(super) const MI_UINT64: u32 = 13;
pub(super) const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
pub(super) const MI_UTF8: u32 = 16;
pub(super) const MI_UTF16: u32 = 17;
pub(super) const MI_UTF32: u32 = 18;

/// Array classes, the low byte of the array flags (table 1-3).
const MX_CELL: u32 = 1;
const MX_STRUCT: u32 = 2;
const MX_OBJECT: u32 = 3;
const MX_CHAR: u32 = 4;
const MX_SPARSE: u32 = 5;
const MX_DOUBLE: u32 = 6;
const MX_UINT64: u32 = 15;
const MX_FUNCTION: u32 = 16;
const MX_OPAQUE: u32 = 17;
/// The complex bit of the array flags.
const FLAG_COMPLEX: u32 = 0x0800;

/// Deepest struct/cell nesting read: dSPACE recordings nest 3 levels; deeper is hostile.
const MAX_DEPTH: usize = 32;
/// Most dimensions of one array: MATLAB data of a test has 2; more is garbage.
const MAX_DIMS: usize = 32;
/// Longest struct field name slot: MATLAB writes 32 or 64 bytes.
pub(super) const MAX_FIELD_NAME_LEN: usize = 4096;
/// Inflated bytes read to find the name of a compressed variable the file cuts short: its
/// flags, dimensions and name take a few dozen bytes (a 4096-byte field-name slot at most).
const PEEK_INFLATED_BYTES: u64 = 8192;
/// Most elements of a struct array without fields (which take no bytes to store).
pub(super) const MAX_FIELDLESS_ELEMENTS: usize = 1 << 20;

/// One data element: its type, where its tag starts, and its data bytes `data_at..end`.
#[derive(Clone, Copy)]
pub(super) struct Element {
    pub(super) mi_type: u32,
    pub(super) at: usize,
    pub(super) data_at: usize,
    pub(super) end: usize,
}

/// Reads data elements, knowing the byte order, the budget of inflated bytes left, and
/// where it is (compressed element, variable and field path) for error messages.
pub(super) struct Parser<'f> {
    file: &'f str,
    big_endian: bool,
    inflate_budget: usize,
    /// The budget at the start, for the message when it runs out.
    inflate_limit: usize,
    /// File offset of the compressed element being read (offsets are then in its inflated bytes).
    compressed_at: Option<usize>,
    /// Variable, field and element path, e.g. ["rec", ".Y(2)", ".Data"].
    pub(super) context: Vec<String>,
}

impl<'f> Parser<'f> {
    pub(super) fn new(file: &'f str, big_endian: bool, inflate_budget: usize) -> Self {
        Parser {
            file,
            big_endian,
            inflate_budget,
            inflate_limit: inflate_budget,
            compressed_at: None,
            context: Vec::new(),
        }
    }

    pub(super) fn err(&self, at: usize, why: impl Into<String>) -> MatError {
        let at = match self.compressed_at {
            Some(c) => format!("byte {at} of the compressed variable at byte {c}"),
            None => format!("byte {at}"),
        };
        let context = match self.context.concat() {
            path if path.is_empty() => String::new(),
            path => format!("variable `{path}`, "),
        };
        MatError::Malformed {
            file: self.file.to_string(),
            context,
            at,
            why: why.into(),
        }
    }

    /// `N` bytes of `c` in little-endian order, whatever the file's order.
    pub(super) fn le<const N: usize>(&self, c: &[u8]) -> [u8; N] {
        let mut a = [0u8; N];
        a.copy_from_slice(&c[..N]);
        if self.big_endian {
            a.reverse();
        }
        a
    }

    pub(super) fn u32_at(&self, buf: &[u8], at: usize, end: usize) -> Result<u32, MatError> {
        match buf.get(at..at.saturating_add(4)) {
            Some(c) if at + 4 <= end => Ok(u32::from_le_bytes(self.le(c))),
            _ => Err(self.err(at, "truncated: a tag runs past the end of its element")),
        }
    }

    /// The element whose tag is at `*pos`; moves `*pos` past it and its padding to 8 bytes.
    pub(super) fn element(
        &self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
    ) -> Result<Element, MatError> {
        let at = *pos;
        let word = self.u32_at(buf, at, end)?;
        if word >> 16 != 0 {
            // Small data element: byte count in the high half, data in the tag's second word.
            let n = (word >> 16) as usize;
            if n > 4 || end - at < 8 {
                return Err(self.err(at, format!("bad small data element ({n} bytes)")));
            }
            *pos = at + 8;
            return Ok(Element {
                mi_type: word & 0xffff,
                at,
                data_at: at + 4,
                end: at + 4 + n,
            });
        }
        let n = self.u32_at(buf, at + 4, end)? as usize;
        let data_at = at + 8;
        if n > end - data_at {
            let left = end - data_at;
            return Err(self.err(at, format!("element of {n} bytes but only {left} remain")));
        }
        let data_end = data_at + n;
        *pos = (data_end + (8 - n % 8) % 8).min(end);
        Ok(Element {
            mi_type: word,
            at,
            data_at,
            end: data_end,
        })
    }

    /// The element at `*pos`, which must be of type `want` (named in the error).
    pub(super) fn expect(
        &self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
        want: &[u32],
        what: &str,
    ) -> Result<Element, MatError> {
        let el = self.element(buf, pos, end)?;
        if !want.contains(&el.mi_type) {
            return Err(self.err(el.at, format!("{what} stored as data type {}", el.mi_type)));
        }
        Ok(el)
    }

    /// Every variable after the header.
    /// Every variable after the header, in file order. A variable without a name is
    /// MATLAB's subsystem data (the contents of objects), not the user's: it is left out.
    pub(super) fn variables(&mut self, bytes: &[u8]) -> Result<Vec<(String, MatValue)>, MatError> {
        let mut variables = Vec::new();
        let mut pos = HEADER_LEN;
        while !only_padding_left(bytes, pos) {
            let at = pos;
            let el = self
                .element(bytes, &mut pos, bytes.len())
                .map_err(|e| self.name_cut_variable(bytes, at, e))?;
            match el.mi_type {
                MI_MATRIX => variables.push(self.matrix(bytes, el, 0)?),
                MI_COMPRESSED => {
                    pos = el.end; // compressed elements are not padded
                    let inflated = self
                        .inflate(bytes, el)
                        .map_err(|e| self.name_cut_variable(bytes, at, e))?;
                    self.compressed_at = Some(el.at);
                    let mut inner = 0;
                    while !only_padding_left(&inflated, inner) {
                        let what = "a compressed variable";
                        let m =
                            self.expect(&inflated, &mut inner, inflated.len(), &[MI_MATRIX], what)?;
                        variables.push(self.matrix(&inflated, m, 0)?);
                    }
                    self.compressed_at = None;
                }
                t => {
                    let why = format!("top-level element of type {t}, not a variable (14 or 15)");
                    return Err(self.err(el.at, why));
                }
            }
        }
        variables.retain(|(name, _)| !name.is_empty());
        Ok(variables)
    }

    /// Error `e` about the top-level element at `at` (a file cut inside it, a zlib stream
    /// that ends early or inflates past the budget) with the name of the variable it holds,
    /// when its first bytes give it.
    fn name_cut_variable(&self, bytes: &[u8], at: usize, e: MatError) -> MatError {
        match (e, self.peek_name(bytes, at)) {
            (
                MatError::Malformed {
                    file,
                    context,
                    at,
                    why,
                },
                Some(name),
            ) if context.is_empty() => MatError::Malformed {
                file,
                context: format!("variable `{name}`, "),
                at,
                why,
            },
            (e, _) => e,
        }
    }

    /// The name of the variable whose top-level element starts at `at`, read from its
    /// first bytes only (inflating at most [`PEEK_INFLATED_BYTES`] of a compressed one).
    fn peek_name(&self, bytes: &[u8], at: usize) -> Option<String> {
        let mi_type = self.u32_at(bytes, at, bytes.len()).ok()?;
        let data = bytes.get(at.checked_add(8)?..)?;
        match mi_type {
            MI_MATRIX => self.name_of_matrix(data, 0),
            MI_COMPRESSED => {
                let mut head = Vec::new();
                // a stream cut short still yields the bytes before the cut
                let _ = flate2::read::ZlibDecoder::new(data)
                    .take(PEEK_INFLATED_BYTES)
                    .read_to_end(&mut head);
                (self.u32_at(&head, 0, head.len()).ok()? == MI_MATRIX)
                    .then(|| self.name_of_matrix(&head, 8))
                    .flatten()
            }
            _ => None,
        }
    }

    /// The name of the miMATRIX whose data starts at `pos` of `buf` (flags, dimensions, name).
    fn name_of_matrix(&self, buf: &[u8], mut pos: usize) -> Option<String> {
        let end = buf.len();
        self.expect(buf, &mut pos, end, &[MI_UINT32], "the array flags")
            .ok()?;
        self.dims(buf, &mut pos, end).ok()?;
        let name = self
            .expect(
                buf,
                &mut pos,
                end,
                &[MI_INT8, MI_UINT8, MI_UTF8],
                "the name",
            )
            .ok()?;
        Some(text_until_nul(&buf[name.data_at..name.end])).filter(|n| !n.is_empty())
    }

    /// The zlib stream of a compressed element, within the file's inflated-bytes budget.
    fn inflate(&mut self, bytes: &[u8], el: Element) -> Result<Vec<u8>, MatError> {
        let mut out = Vec::new();
        let limit = self.inflate_budget as u64 + 1;
        flate2::read::ZlibDecoder::new(&bytes[el.data_at..el.end])
            .take(limit)
            .read_to_end(&mut out)
            .map_err(|e| self.err(el.at, format!("compressed variable does not inflate: {e}")))?;
        if out.len() > self.inflate_budget {
            let why = format!(
                "compressed variables inflate to more than {} bytes in all",
                self.inflate_limit
            );
            return Err(self.err(el.at, why));
        }
        self.inflate_budget -= out.len();
        Ok(out)
    }

    /// One miMATRIX element: its name and value.
    pub(super) fn matrix(
        &mut self,
        buf: &[u8],
        el: Element,
        depth: usize,
    ) -> Result<(String, MatValue), MatError> {
        if depth > MAX_DEPTH {
            return Err(self.err(
                el.at,
                format!("structs or cells nested deeper than {MAX_DEPTH}"),
            ));
        }
        if el.data_at == el.end {
            // MATLAB writes an empty value inside a struct or cell as a bare tag.
            return Ok((
                String::new(),
                MatValue::Numeric {
                    dims: vec![0, 0],
                    data: vec![],
                },
            ));
        }
        let (mut pos, end) = (el.data_at, el.end);
        let flags = self.expect(buf, &mut pos, end, &[MI_UINT32], "the array flags")?;
        let word = self.u32_at(buf, flags.data_at, flags.end)?;
        let dims = self.dims(buf, &mut pos, end)?;
        let name_el = self.expect(
            buf,
            &mut pos,
            end,
            &[MI_INT8, MI_UINT8, MI_UTF8],
            "the array name",
        )?;
        let name = text_until_nul(&buf[name_el.data_at..name_el.end]);
        let top = depth == 0;
        if top {
            self.context.push(name.clone());
        }
        let value = self.array(buf, (pos, end), word, dims, depth);
        if top {
            self.context.pop();
        }
        Ok((name, value?))
    }

    /// The class-specific part of an array whose flags word and dims are read.
    fn array(
        &mut self,
        buf: &[u8],
        (mut pos, end): (usize, usize),
        word: u32,
        dims: Vec<usize>,
        depth: usize,
    ) -> Result<MatValue, MatError> {
        let class = word & 0xff;
        match class {
            MX_CELL => self.cell(buf, &mut pos, end, dims, depth),
            MX_STRUCT => self.structure(buf, &mut pos, end, dims, depth),
            MX_CHAR => self.chars(buf, &mut pos, end, &dims),
            MX_DOUBLE..=MX_UINT64 if word & FLAG_COMPLEX != 0 => {
                Ok(MatValue::Unsupported("complex numeric array".into()))
            }
            MX_DOUBLE..=MX_UINT64 => self.numeric(buf, &mut pos, end, dims),
            MX_SPARSE => Ok(MatValue::Unsupported("sparse matrix".into())),
            MX_OBJECT => Ok(MatValue::Unsupported("MATLAB object".into())),
            MX_FUNCTION => Ok(MatValue::Unsupported("function handle".into())),
            MX_OPAQUE => Ok(MatValue::Unsupported(
                "opaque object (string, table, timeseries, ...)".into(),
            )),
            other => Ok(MatValue::Unsupported(format!(
                "array of unknown class {other}"
            ))),
        }
    }

    fn dims(&self, buf: &[u8], pos: &mut usize, end: usize) -> Result<Vec<usize>, MatError> {
        let el = self.expect(buf, pos, end, &[MI_INT32, MI_UINT32], "the dimensions")?;
        let raw = &buf[el.data_at..el.end];
        if !raw.len().is_multiple_of(4) || raw.is_empty() || raw.len() / 4 > MAX_DIMS {
            return Err(self.err(el.at, format!("dimensions of {} bytes", raw.len())));
        }
        raw.chunks_exact(4)
            .map(|c| {
                usize::try_from(i32::from_le_bytes(self.le(c)))
                    .map_err(|_| self.err(el.at, "a negative dimension"))
            })
            .collect()
    }

    /// Number of elements of `dims`, refused when it overflows.
    pub(super) fn count(&self, at: usize, dims: &[usize]) -> Result<usize, MatError> {
        dims.iter()
            .try_fold(1usize, |n, &d| n.checked_mul(d))
            .ok_or_else(|| self.err(at, format!("absurd dimensions {dims:?}")))
    }
}

/// Whether nothing but fewer than 8 zero bytes (alignment padding) follows `pos`.
fn only_padding_left(buf: &[u8], pos: usize) -> bool {
    buf.get(pos..)
        .is_none_or(|rest| rest.len() < 8 && rest.iter().all(|&b| b == 0))
}

/// Bytes up to the first NUL, as text (names are ASCII; anything else is kept lossily).
pub(super) fn text_until_nul(raw: &[u8]) -> String {
    let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
    String::from_utf8_lossy(&raw[..end]).into_owned()
}
