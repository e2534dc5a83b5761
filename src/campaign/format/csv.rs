//! CSV records: parsing, the time-column rules and the record built from the columns.

use super::*;

/// A parsed text record: column names, columns, and the physical line of the header
/// (0 when the file has none) and of every data row. In a lenient parse a column that
/// is not all finite numbers keeps its first bad cell in `bad`: an error only when the
/// column is used.
pub(super) struct CsvTable {
    pub(super) names: Vec<String>,
    pub(super) columns: Vec<Vec<f64>>,
    pub(super) bad: Vec<Option<(usize, String)>>,
    pub(super) header_line: usize,
    pub(super) row_lines: Vec<usize>,
}

impl CsvTable {
    pub(super) fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    pub(super) fn take(&mut self, name: &str) -> Option<Vec<f64>> {
        self.index(name)
            .map(|i| std::mem::take(&mut self.columns[i]))
    }
}

pub(super) fn unquote(cell: &str) -> &str {
    let c = cell.trim();
    if c.len() >= 2 && c.starts_with('"') && c.ends_with('"') {
        c[1..c.len() - 1].trim()
    } else {
        c
    }
}

/// The cells of one line under `opts`' delimiter.
fn cells<'a>(line: &'a str, opts: &ReadOptions) -> Vec<&'a str> {
    match opts.delimiter {
        Delimiter::Whitespace => line.split_whitespace().collect(),
        Delimiter::Char(c) => line.split(c).collect(),
    }
}

/// A cell as a finite number, or the message saying why not. With a decimal comma the
/// cell is rewritten into `buffer` first (one buffer for the whole file: no allocation
/// per cell).
fn cell_value(name: &str, c: &str, decimal: Decimal, buffer: &mut String) -> Result<f64, String> {
    let text = match decimal {
        Decimal::Comma if c.contains(',') => {
            buffer.clear();
            buffer.extend(c.chars().map(|ch| if ch == ',' { '.' } else { ch }));
            buffer.as_str()
        }
        _ => c,
    };
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!(
            "channel `{name}`: `{c}` is not finite (NaN or infinity)"
        )),
        Err(_) if c.is_empty() => Err(format!("channel `{name}`: empty cell")),
        Err(_) => Err(format!("channel `{name}`: `{c}` is not a number")),
    }
}

/// A record error at physical line `line` of `file`.
fn csv_error(file: &str, line: usize, message: String) -> CampaignError {
    CampaignError::Csv {
        file: file.to_string(),
        line,
        message,
    }
}

/// The header's column names (checked), or `1, 2, ...` for a file without one.
fn header_names(cells: &[&str], line_no: usize, file: &str) -> Result<Vec<String>, CampaignError> {
    let err = |message: String| csv_error(file, line_no, message);
    let mut names: Vec<String> = Vec::new();
    for (j, cell) in cells.iter().enumerate() {
        let name = unquote(cell);
        if name.is_empty() {
            return Err(err(format!("header: column {} has no name", j + 1)));
        }
        if names.iter().any(|n| n == name) {
            return Err(err(format!("header: channel `{name}` appears twice")));
        }
        if name.parse::<f64>().is_ok() {
            return Err(err(format!(
                "header expected (channel names), found the number `{name}`"
            )));
        }
        names.push(name.to_string());
    }
    Ok(names)
}

/// Parse a text record under `opts` (campaign-format.md; `[read]`). `strict` is the
/// project's own form: every cell a finite number and every row as long as the header.
/// Otherwise (a laboratory's file read in place) columns may hold text (a date, an event
/// note) and rows may end early (empty trailing cells): such cells are errors only in a
/// column that is used. A row longer than the header is always an error.
pub(super) fn parse_csv(
    text: &str,
    file: &str,
    opts: &ReadOptions,
    strict: bool,
) -> Result<CsvTable, CampaignError> {
    check_decimal_delimiter(opts, file)?;
    // a UTF-8 byte-order mark (spreadsheet exports) is not part of the first channel name
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut reader = CsvReader::new(file, opts, strict, text.len());
    for (i, line) in lines_any(text).enumerate() {
        let line_no = i + 1;
        let trimmed = line.trim_start();
        if matches!(opts.header_line, Some(h) if line_no < h) || trimmed.is_empty() {
            continue;
        }
        reader.last_line = line_no;
        if !opts.comment.is_empty() && trimmed.starts_with(opts.comment.as_str()) {
            continue;
        }
        let row = cells(line, opts);
        if !reader.have_names && reader.first_row(&row, line, line_no)? {
            continue;
        }
        reader.data_row(&row, line_no)?;
    }
    reader.finish()
}

/// `[read]` must not give a decimal comma with a comma delimiter: a number's comma
/// could not be told from a cell separator.
fn check_decimal_delimiter(opts: &ReadOptions, file: &str) -> Result<(), CampaignError> {
    if opts.decimal == Decimal::Comma && opts.delimiter == Delimiter::Char(',') {
        return Err(CampaignError::Invalid {
            file: file.to_string(),
            message: "[read] decimal = \",\" with delimiter = \",\": a number's comma could not \
                      be told from the cells' separator; set the delimiter the file uses \
                      (\";\" or \"\\t\")"
                .to_string(),
        });
    }
    Ok(())
}

/// A text record while [`parse_csv`] reads it, line by line: the table so far, whether
/// its names are known, and the last line that is neither blank nor before the header.
struct CsvReader<'a> {
    file: &'a str,
    opts: &'a ReadOptions,
    strict: bool,
    /// The length of the whole text (to size the columns from the header's length).
    text_len: usize,
    table: CsvTable,
    have_names: bool,
    last_line: usize,
    /// One buffer for the decimal-comma rewrite of every cell.
    buffer: String,
}

impl<'a> CsvReader<'a> {
    fn new(file: &'a str, opts: &'a ReadOptions, strict: bool, text_len: usize) -> Self {
        CsvReader {
            file,
            opts,
            strict,
            text_len,
            table: CsvTable {
                names: Vec::new(),
                columns: Vec::new(),
                bad: Vec::new(),
                header_line: 0,
                row_lines: Vec::new(),
            },
            have_names: false,
            last_line: 0,
            buffer: String::new(),
        }
    }

    /// The first row read names the columns: the header (checked; returns true, the row
    /// holds no samples), or, with `header_line = 0`, `1, 2, ...` (returns false).
    fn first_row(
        &mut self,
        row: &[&str],
        line: &str,
        line_no: usize,
    ) -> Result<bool, CampaignError> {
        self.have_names = true;
        let t = &mut self.table;
        if self.opts.header_line == Some(0) {
            t.names = (1..=row.len()).map(|j| j.to_string()).collect();
            t.columns = (0..t.names.len()).map(|_| Vec::new()).collect();
            t.bad = vec![None; t.names.len()];
            return Ok(false);
        }
        t.header_line = line_no;
        t.names = header_names(row, line_no, self.file)?;
        let cap = self.text_len / (line.len() + 1).max(8);
        t.columns = (0..t.names.len())
            .map(|_| Vec::with_capacity(cap))
            .collect();
        t.bad = vec![None; t.names.len()];
        Ok(true)
    }

    /// One row of samples: a value (or, leniently, NaN and the cell's error) per column,
    /// NaN and "empty cell" for the columns a short row leaves out.
    fn data_row(&mut self, row: &[&str], line_no: usize) -> Result<(), CampaignError> {
        let t = &mut self.table;
        let width = t.names.len();
        for (j, cell) in row.iter().enumerate().take(width) {
            match cell_value(
                &t.names[j],
                unquote(cell),
                self.opts.decimal,
                &mut self.buffer,
            ) {
                Ok(v) => t.columns[j].push(v),
                Err(m) if self.strict => return Err(csv_error(self.file, line_no, m)),
                Err(m) => {
                    t.columns[j].push(f64::NAN);
                    t.bad[j].get_or_insert((line_no, m));
                }
            }
        }
        self.check_width(row, line_no)?;
        let t = &mut self.table;
        for j in row.len()..width {
            t.columns[j].push(f64::NAN);
            let m = format!("channel `{}`: empty cell", t.names[j]);
            t.bad[j].get_or_insert((line_no, m));
        }
        t.row_lines.push(line_no);
        Ok(())
    }

    /// A row is not longer than the header (nor, strictly, shorter).
    fn check_width(&self, row: &[&str], line_no: usize) -> Result<(), CampaignError> {
        let t = &self.table;
        let width = t.names.len();
        // a lab file's last column may be a text note that holds the delimiter itself
        // (a DAQ's "DAQ Pause, DAQ Stop" event): when nothing can map it (it is already
        // text), the surplus cells are the rest of that note
        let text_tail = !self.strict && width > 0 && t.bad[width - 1].is_some();
        if (row.len() > width && !text_tail) || (self.strict && row.len() < width) {
            let header = match t.header_line {
                0 => "the first row".to_string(),
                h => format!("the header (line {h})"),
            };
            return Err(csv_error(
                self.file,
                line_no,
                format!(
                    "ragged row: {} cells but {header} has {width} channels",
                    row.len()
                ),
            ));
        }
        Ok(())
    }

    /// The table, once the text is read: it must have names and at least one row.
    fn finish(self) -> Result<CsvTable, CampaignError> {
        let t = self.table;
        if !self.have_names {
            return Err(csv_error(
                self.file,
                self.last_line.max(1),
                "empty record: no header line and no samples".to_string(),
            ));
        }
        if t.row_lines.is_empty() {
            return Err(csv_error(
                self.file,
                if t.header_line > 0 {
                    t.header_line
                } else {
                    self.last_line.max(1)
                },
                "empty record: a header but no samples".to_string(),
            ));
        }
        Ok(t)
    }
}

pub(super) fn require_channels(
    t: &CsvTable,
    required: &[&str],
    file: &str,
) -> Result<(), CampaignError> {
    let missing: Vec<&str> = required
        .iter()
        .copied()
        .filter(|c| t.index(c).is_none())
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(CampaignError::Csv {
        file: file.to_string(),
        line: t.header_line,
        message: format!(
            "missing required channel{} {} (the header has: {})",
            if missing.len() > 1 { "s" } else { "" },
            missing
                .iter()
                .map(|c| format!("`{c}`"))
                .collect::<Vec<_>>()
                .join(", "),
            t.names.join(", ")
        ),
    })
}

/// Check the time column: strictly increasing; its own rate (see [`TimeGrid`]) within
/// [`RATE_TOLERANCE`] of `sample_rate_hz` (or, when `None`, taken as the rate); every
/// sample on its uniform grid. Returns the sample rate.
pub(super) fn check_time(
    t: &CsvTable,
    time: &[f64],
    sample_rate_hz: Option<f64>,
    rate_source: &str,
    file: &str,
) -> Result<f64, CampaignError> {
    let column = TimeColumn { t, time, file };
    column.check_increasing()?;
    if time.len() < 2 {
        return match sample_rate_hz {
            Some(fs) => Ok(fs),
            None => Err(column.err(
                0,
                "a single sample: the sample rate cannot be inferred from time_s".to_string(),
            )),
        };
    }
    let grid = TimeGrid::fit(time);
    let fs = match sample_rate_hz {
        Some(fs) => column.check_rate(&grid, fs, rate_source)?,
        None => {
            let fs = grid.rate_hz();
            if (fs - fs.round()).abs() < 1e-6 * fs {
                fs.round()
            } else {
                fs
            }
        }
    };
    column.check_on_grid(&grid)?;
    Ok(fs)
}

/// A record's time column with the table it came from (for the lines of its samples)
/// and the file's name, for [`check_time`]'s errors.
struct TimeColumn<'a> {
    t: &'a CsvTable,
    time: &'a [f64],
    file: &'a str,
}

impl TimeColumn<'_> {
    /// An error at the line of sample `k`.
    fn err(&self, k: usize, message: String) -> CampaignError {
        csv_error(self.file, self.t.row_lines[k], message)
    }

    /// Every sample later than the one before it.
    fn check_increasing(&self) -> Result<(), CampaignError> {
        let (time, rows) = (self.time, &self.t.row_lines);
        match (1..time.len()).find(|&k| time[k] <= time[k - 1]) {
            Some(k) => Err(self.err(
                k,
                format!(
                    "time_s is not increasing: {} after {} (line {})",
                    time[k],
                    time[k - 1],
                    rows[k - 1]
                ),
            )),
            None => Ok(()),
        }
    }

    /// The declared rate `fs` (from `rate_source`) agrees with the grid's within
    /// [`RATE_TOLERANCE`]; returns it.
    fn check_rate(
        &self,
        grid: &TimeGrid,
        fs: f64,
        rate_source: &str,
    ) -> Result<f64, CampaignError> {
        let clock = grid.rate_hz();
        if ((clock - fs) / fs).abs() > RATE_TOLERANCE {
            return Err(self.err(
                1,
                format!(
                    "sample rate disagrees: time column gives {} Hz, {rate_source} says {} Hz \
                     (more than {} % apart)",
                    num(round_sig(clock, 7)),
                    num(fs),
                    RATE_TOLERANCE * 100.0
                ),
            ));
        }
        Ok(fs)
    }

    /// Every sample on the column's own uniform grid ([`TimeGrid::first_off_grid`]).
    fn check_on_grid(&self, grid: &TimeGrid) -> Result<(), CampaignError> {
        let Some(k) = grid.first_off_grid(self.time) else {
            return Ok(());
        };
        let time = self.time;
        let expected = grid.at(k as f64);
        // a start at 0 shows as 0, not as the fit's rounding residue
        let t0 = if grid.t0.abs() < 1e-6 * grid.step {
            0.0
        } else {
            grid.t0
        };
        Err(self.err(
            k,
            format!(
                "non-uniform time: sample {k} is at time_s = {} but the time column's own \
                 uniform grid ({} Hz from {}) puts it at {} (step here {} s, expected {} s)",
                time[k],
                num(round_sig(grid.rate_hz(), 7)),
                num(t0),
                num(expected),
                num(round_sig(
                    if k > 0 { time[k] - time[k - 1] } else { 0.0 },
                    6
                )),
                num(round_sig(grid.step, 6)),
            ),
        ))
    }
}

/// `x` for a message: 9 significant digits, exponent notation when very large or small.
pub(super) fn num(x: f64) -> String {
    let r = round_sig(x, 9);
    if r != 0.0 && r.is_finite() && (r.abs() >= 1e7 || r.abs() < 1e-4) {
        format!("{r:e}")
    } else {
        format!("{r}")
    }
}

/// `x` rounded to `digits` significant digits (for messages).
pub(super) fn round_sig(x: f64, digits: usize) -> f64 {
    format!("{x:.*e}", digits.saturating_sub(1))
        .parse()
        .unwrap_or(x)
}

/// The uniform grid a time column follows: `t0 + j * step`, fitted by least squares over
/// every sample, where `j` counts steps of the median step (so a gap counts as two steps
/// and does not bias the fit). The rate rule compares `1 / step` with the declared rate;
/// the uniformity rule compares each sample with this grid, so a small constant rate
/// offset never accumulates into "non-uniform time", and jitter, gaps and drift still do.
#[derive(Clone, Copy)]
pub(super) struct TimeGrid {
    t0: f64,
    step: f64,
    median: f64,
}

impl TimeGrid {
    /// Fit the grid of a strictly increasing time column of at least 2 samples: a least
    /// squares line, then again without the samples off that line (so one late sample
    /// does not tilt the grid of a short record).
    fn fit(time: &[f64]) -> TimeGrid {
        let mut steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
        let mid = steps.len() / 2;
        let (_, &mut median, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
        let first = TimeGrid {
            t0: time[0],
            step: median,
            median,
        }
        .refit(time, None);
        first.refit(time, Some(GRID_TOLERANCE * first.step))
    }

    /// The least-squares grid of the samples within `tol` of this grid (all if `None`).
    fn refit(&self, time: &[f64], tol: Option<f64>) -> TimeGrid {
        let keep = |j: f64, t: f64| tol.is_none_or(|tol| (t - self.at(j)).abs() <= tol);
        let (mut n, mut sj, mut st) = (0.0, 0.0, 0.0);
        for (j, &t) in self.indices(time).zip(time) {
            if keep(j, t) {
                (n, sj, st) = (n + 1.0, sj + j, st + t);
            }
        }
        let (mj, mt) = (sj / n, st / n);
        let (mut sjt, mut sjj) = (0.0, 0.0);
        for (j, &t) in self.indices(time).zip(time) {
            if keep(j, t) {
                sjt += (j - mj) * (t - mt);
                sjj += (j - mj) * (j - mj);
            }
        }
        if !(n >= 2.0 && sjj > 0.0 && sjt > 0.0) {
            return *self;
        }
        let step = sjt / sjj;
        TimeGrid {
            t0: mt - step * mj,
            step,
            median: self.median,
        }
    }

    /// The grid time of index `j`.
    fn at(&self, j: f64) -> f64 {
        self.t0 + j * self.step
    }

    fn rate_hz(&self) -> f64 {
        1.0 / self.step
    }

    /// The grid index of every sample: each step counts as a whole number of median
    /// steps (1 normally, 2 across a missing sample), added one step at a time so that
    /// a small rate offset never rounds to the wrong index.
    fn indices<'a>(&self, time: &'a [f64]) -> impl Iterator<Item = f64> + 'a {
        let median = self.median;
        let mut j = 0.0;
        let mut prev = time[0];
        time.iter().map(move |&t| {
            j += ((t - prev) / median).round();
            prev = t;
            j
        })
    }

    /// The first sample off its place `t0 + k * step` by more than [`GRID_TOLERANCE`]
    /// of a step (jitter, drift), or where a step is not one step (a gap, a doubled sample).
    fn first_off_grid(&self, time: &[f64]) -> Option<usize> {
        let tol = GRID_TOLERANCE * self.step;
        self.indices(time)
            .zip(time)
            .enumerate()
            .position(|(k, (j, &t))| j != k as f64 || (t - self.at(j)).abs() > tol)
    }
}

pub(super) fn record_from_table(mut t: CsvTable) -> Record {
    let mut take = |name: &str| t.take(name).unwrap_or_default();
    let time_s = take("time_s");
    let ref_displacement_m = take("ref_displacement_m");
    let ref_velocity_m_s = take("ref_velocity_m_s");
    let ref_acceleration_m_s2 = take("ref_acceleration_m_s2");
    let valve_command = take("valve_command");
    let displacement_m = take("displacement_m");
    let acceleration_m_s2 = take("acceleration_m_s2");
    let force_n = take("force_n");
    let spool_position = t.take(SPOOL_CHANNEL);
    let known: Vec<&str> = REQUIRED_CHANNELS
        .iter()
        .copied()
        .chain(std::iter::once(SPOOL_CHANNEL))
        .collect();
    let extra = t
        .names
        .iter()
        .zip(t.columns.iter_mut())
        .filter(|(n, _)| !known.contains(&n.as_str()))
        .map(|(n, c)| (n.clone(), std::mem::take(c)))
        .collect();
    Record {
        time_s,
        ref_displacement_m,
        ref_velocity_m_s,
        ref_acceleration_m_s2,
        valve_command: Some(valve_command),
        spool_position,
        displacement_m: Some(displacement_m),
        acceleration_m_s2: Some(acceleration_m_s2),
        force_n: Some(force_n),
        extra,
    }
}
