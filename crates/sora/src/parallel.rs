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

/// [`for_each_chunk_mut`] with work space: `work(state, chunk_index,
/// chunk)`, where `state` is made by `init` once per run of chunks that one
/// thread takes in turn (rayon's `for_each_init`), not once per chunk, so
/// a large buffer is allocated (and its pages touched) a few times instead
/// of once per chunk. `work` must not depend on what an earlier chunk left
/// in `state` (results do not depend on the number of threads).
pub(crate) fn for_each_chunk_mut_with<T: Send, S>(
    data: &mut [T],
    chunk_length: usize,
    init: impl Fn() -> S + Sync + Send,
    work: impl Fn(&mut S, usize, &mut [T]) + Sync + Send,
) {
    if data.is_empty() {
        return;
    }
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        data.par_chunks_mut(chunk_length)
            .enumerate()
            .for_each_init(init, |state, (i, chunk)| work(state, i, chunk));
    }
    #[cfg(not(feature = "parallel"))]
    {
        let mut state = init();
        data.chunks_mut(chunk_length)
            .enumerate()
            .for_each(|(i, chunk)| work(&mut state, i, chunk));
    }
}

/// A vector of `len` copies of `value`, written in parallel when enabled
/// (a large buffer's pages are then touched by every thread, not one).
pub(crate) fn filled<T: Copy + Send + Sync>(len: usize, value: T) -> Vec<T> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        let mut out = Vec::new();
        (0..len)
            .into_par_iter()
            .map(|_| value)
            .collect_into_vec(&mut out);
        out
    }
    #[cfg(not(feature = "parallel"))]
    {
        vec![value; len]
    }
}

/// `work(chunk)` for every `chunk_length` chunk of `data` (the last may
/// be shorter), in order, computed in parallel when enabled.
pub(crate) fn map_chunks<T: Sync, R: Send>(
    data: &[T],
    chunk_length: usize,
    work: impl Fn(&[T]) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        data.par_chunks(chunk_length).map(work).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        data.chunks(chunk_length).map(work).collect()
    }
}
