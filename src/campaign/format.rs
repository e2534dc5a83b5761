//! Reading and writing campaigns on disk (campaign-format.md).
