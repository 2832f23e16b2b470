//! STL and loop-CSV readers (placeholder).
