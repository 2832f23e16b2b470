//! Heap bytes held by buffers (their capacities), for the memory accessors of the solvers.

/// Bytes of `v`'s heap buffer: its capacity, not its length.
pub(crate) fn vec_bytes<T>(v: &Vec<T>) -> usize {
    v.capacity() * std::mem::size_of::<T>()
}
