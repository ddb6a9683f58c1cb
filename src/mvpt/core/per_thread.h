// Scratch buffers kept per thread between calls (the wavefront's path records, a tile's
// sample lists), so that a batch does not allocate.
#pragma once

namespace mvpt {

/// The calling thread's instance of T, made on its first use. Not inlined, so that a caller
/// holds the returned reference: an inlined thread_local's address may be recomputed at each
/// use, a __tls_get_addr call in a shared library such as the Python module.
template <class T> [[gnu::noinline]] T &per_thread() {
    thread_local T value;
    return value;
}

} // namespace mvpt
