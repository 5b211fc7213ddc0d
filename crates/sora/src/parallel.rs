//! Data parallelism behind one switch: with the `parallel` feature
//! (default) work is spread over threads with rayon; without it (e.g. for
//! WebAssembly) the same loops run sequentially. Either way every chunk is
//! computed by the same code from the same inputs, so results do not
//! depend on the number of threads.

/// Calls `work(chunk_index, chunk)` for every `chunk_length` chunk of
/// `data` (the last may be shorter), in parallel when enabled. Empty data
/// (e.g. per-species work for an atmosphere without species) has no chunks,
/// whatever the chunk length.
pub(crate) fn for_each_chunk_mut<T: Send>(
    data: &mut [T],
    chunk_length: usize,
    work: impl Fn(usize, &mut [T]) + Sync + Send,
) {
    if data.is_empty() {
        return;
    }
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        data.par_chunks_mut(chunk_length)
            .enumerate()
            .for_each(|(i, chunk)| work(i, chunk));
    }
    #[cfg(not(feature = "parallel"))]
    {
        data.chunks_mut(chunk_length)
            .enumerate()
            .for_each(|(i, chunk)| work(i, chunk));
    }
}
