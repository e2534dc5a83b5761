//! Figures (plotters) and Markdown/HTML report pages.
