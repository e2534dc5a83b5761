//! The class-specific part of an array: numbers, chars, struct fields and cells.

use super::parse::{
    text_until_nul, Element, Parser, MAX_FIELDLESS_ELEMENTS, MAX_FIELD_NAME_LEN, MI_DOUBLE,
    MI_INT16, MI_INT32, MI_INT64, MI_INT8, MI_MATRIX, MI_SINGLE, MI_UINT16, MI_UINT32, MI_UINT64,
    MI_UINT8, MI_UTF16, MI_UTF32, MI_UTF8,
};
use super::{MatError, MatValue};

impl Parser<'_> {
    pub(super) fn numeric(
        &self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
        dims: Vec<usize>,
    ) -> Result<MatValue, MatError> {
        let at = *pos;
        let n = self.count(at, &dims)?;
        if n == 0 && *pos >= end {
            return Ok(MatValue::Numeric { dims, data: vec![] });
        }
        let el = self.element(buf, pos, end)?;
        let data = self.to_f64(&buf[el.data_at..el.end], el)?;
        if data.len() != n {
            return Err(self.err(
                el.at,
                format!("{} values for dimensions {dims:?}", data.len()),
            ));
        }
        Ok(MatValue::Numeric { dims, data })
    }

    /// Numbers stored in any numeric data type (MATLAB stores doubles as miUINT8 when they fit).
    fn to_f64(&self, raw: &[u8], el: Element) -> Result<Vec<f64>, MatError> {
        let size = match el.mi_type {
            MI_INT8 | MI_UINT8 => 1,
            MI_INT16 | MI_UINT16 => 2,
            MI_INT32 | MI_UINT32 | MI_SINGLE => 4,
            MI_DOUBLE | MI_INT64 | MI_UINT64 => 8,
            t => return Err(self.err(el.at, format!("numeric data stored as data type {t}"))),
        };
        if !raw.len().is_multiple_of(size) {
            return Err(self.err(el.at, format!("{} bytes of {size}-byte numbers", raw.len())));
        }
        let t = el.mi_type;
        Ok(raw.chunks_exact(size).map(|c| self.number(t, c)).collect())
    }

    fn number(&self, mi_type: u32, c: &[u8]) -> f64 {
        match mi_type {
            MI_INT8 => c[0] as i8 as f64,
            MI_UINT8 => c[0] as f64,
            MI_INT16 => i16::from_le_bytes(self.le(c)) as f64,
            MI_UINT16 => u16::from_le_bytes(self.le(c)) as f64,
            MI_INT32 => i32::from_le_bytes(self.le(c)) as f64,
            MI_UINT32 => u32::from_le_bytes(self.le(c)) as f64,
            MI_SINGLE => f32::from_le_bytes(self.le(c)) as f64,
            MI_INT64 => i64::from_le_bytes(self.le(c)) as f64,
            MI_UINT64 => u64::from_le_bytes(self.le(c)) as f64,
            _ => f64::from_le_bytes(self.le(c)),
        }
    }

    pub(super) fn chars(
        &self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
        dims: &[usize],
    ) -> Result<MatValue, MatError> {
        if *pos >= end {
            return Ok(MatValue::Char(String::new()));
        }
        let el = self.element(buf, pos, end)?;
        let raw = &buf[el.data_at..el.end];
        let units: Vec<char> = match el.mi_type {
            MI_UTF8 => String::from_utf8_lossy(raw).chars().collect(),
            MI_INT8 | MI_UINT8 => raw.iter().map(|&b| b as char).collect(),
            MI_UINT16 | MI_UTF16 if raw.len().is_multiple_of(2) => {
                let code_units = raw.chunks_exact(2).map(|c| u16::from_le_bytes(self.le(c)));
                char::decode_utf16(code_units)
                    .map(|r| r.unwrap_or(char::REPLACEMENT_CHARACTER))
                    .collect()
            }
            MI_UTF32 | MI_UINT32 | MI_INT32 if raw.len().is_multiple_of(4) => raw
                .chunks_exact(4)
                .map(|c| {
                    char::from_u32(u32::from_le_bytes(self.le(c)))
                        .unwrap_or(char::REPLACEMENT_CHARACTER)
                })
                .collect(),
            t => {
                return Err(self.err(
                    el.at,
                    format!("{} bytes of char data stored as data type {t}", raw.len()),
                ))
            }
        };
        Ok(MatValue::Char(char_rows(units, dims)))
    }

    pub(super) fn structure(
        &mut self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
        dims: Vec<usize>,
        depth: usize,
    ) -> Result<MatValue, MatError> {
        let len_el = self.expect(buf, pos, end, &[MI_INT32], "the field name length")?;
        let name_len = self.u32_at(buf, len_el.data_at, len_el.end)? as usize;
        if name_len == 0 || name_len > MAX_FIELD_NAME_LEN {
            return Err(self.err(len_el.at, format!("field name length {name_len}")));
        }
        let names_el = self.expect(
            buf,
            pos,
            end,
            &[MI_INT8, MI_UINT8, MI_UTF8],
            "the field names",
        )?;
        let raw = &buf[names_el.data_at..names_el.end];
        if !raw.len().is_multiple_of(name_len) {
            return Err(self.err(
                names_el.at,
                format!("{} bytes of {name_len}-byte field names", raw.len()),
            ));
        }
        let fields: Vec<String> = raw.chunks_exact(name_len).map(text_until_nul).collect();
        let n = self.count(len_el.at, &dims)?;
        let fits = match fields.len() {
            0 => n <= MAX_FIELDLESS_ELEMENTS,
            f => n
                .checked_mul(f)
                .and_then(|m| m.checked_mul(8))
                .is_some_and(|b| b <= end - *pos),
        };
        if !fits {
            return Err(self.err(
                names_el.at,
                format!(
                    "{n} elements of {} fields do not fit in the bytes left",
                    fields.len()
                ),
            ));
        }
        let mut elements = Vec::with_capacity(n);
        for e in 0..n {
            let mut values = Vec::with_capacity(fields.len());
            for field in &fields {
                let index = if n == 1 {
                    String::new()
                } else {
                    format!("({})", e + 1)
                };
                self.context.push(format!("{index}.{field}"));
                let value = self.nested(buf, pos, end, depth);
                self.context.pop();
                values.push(value?);
            }
            elements.push(values);
        }
        Ok(MatValue::Struct {
            dims,
            fields,
            elements,
        })
    }

    pub(super) fn cell(
        &mut self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
        dims: Vec<usize>,
        depth: usize,
    ) -> Result<MatValue, MatError> {
        let n = self.count(*pos, &dims)?;
        if n.checked_mul(8).is_none_or(|b| b > end - *pos) {
            return Err(self.err(*pos, format!("{n} cells do not fit in the bytes left")));
        }
        let mut elements = Vec::with_capacity(n);
        for e in 0..n {
            self.context.push(format!("{{{}}}", e + 1));
            let value = self.nested(buf, pos, end, depth);
            self.context.pop();
            elements.push(value?);
        }
        Ok(MatValue::Cell { dims, elements })
    }

    /// A struct field's or cell's value: one miMATRIX element one level deeper.
    fn nested(
        &mut self,
        buf: &[u8],
        pos: &mut usize,
        end: usize,
        depth: usize,
    ) -> Result<MatValue, MatError> {
        let el = self.expect(buf, pos, end, &[MI_MATRIX], "a field or cell value")?;
        Ok(self.matrix(buf, el, depth + 1)?.1)
    }
}

/// A column-major char matrix as its rows joined by `\n` (a row vector is just its text).
fn char_rows(units: Vec<char>, dims: &[usize]) -> String {
    let rows = dims.first().copied().unwrap_or(1);
    if dims.len() != 2 || rows <= 1 || rows.checked_mul(dims[1]) != Some(units.len()) {
        return units.into_iter().collect();
    }
    let cols = dims[1];
    (0..rows)
        .map(|r| (0..cols).map(|c| units[c * rows + r]).collect::<String>())
        .collect::<Vec<_>>()
        .join("\n")
}
