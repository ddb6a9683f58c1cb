// The state file of a render (docs/checkpoints.md): everything its images are made from at a
// pass boundary, so that it can be resumed or merged. Layout: a magic string, the format
// version, a header that the caller writes (JSON naming the scene and the settings), then the
// renderer's fields as length-prefixed blocks, and a checksum of the blocks. A file is written
// under a temporary name and renamed into place: it is complete or absent.
#pragma once

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace mvpt {

/// A state file that cannot be used: not one, truncated, corrupt or of another format.
class StateError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

class StateWriter {
public:
    /// Starts `path`'s temporary file and writes the header.
    StateWriter(const std::string &path, const std::string &header);
    ~StateWriter(); ///< removes the temporary file unless committed
    StateWriter(const StateWriter &) = delete;
    StateWriter &operator=(const StateWriter &) = delete;

    template <typename T> void put(const T &value) {
        static_assert(std::is_trivially_copyable_v<T>);
        block(&value, sizeof(T), 1);
    }
    template <typename T> void put(const std::vector<T> &values) {
        static_assert(std::is_trivially_copyable_v<T>);
        block(values.data(), sizeof(T), values.size());
    }
    /// The checksum, then the file flushed to disk and renamed to its path.
    void commit();

private:
    void block(const void *data, size_t size, size_t count);
    void write(const void *data, size_t bytes);
    std::string m_path, m_tmp;
    std::FILE *m_file = nullptr;
    uint64_t m_hash;
};

class StateReader {
public:
    /// Opens `path` and reads its header; a StateError if it is not a state file of this format.
    explicit StateReader(const std::string &path);
    ~StateReader();
    StateReader(const StateReader &) = delete;
    StateReader &operator=(const StateReader &) = delete;

    const std::string &header() const { return m_header; }
    template <typename T> T get() {
        static_assert(std::is_trivially_copyable_v<T>);
        T value;
        block(&value, sizeof(T), 1);
        return value;
    }
    /// A block of exactly `count` values (the renderer knows its sizes: anything else is corrupt).
    template <typename T> void get(std::vector<T> &values, size_t count) {
        static_assert(std::is_trivially_copyable_v<T>);
        values.resize(count);
        block(values.data(), sizeof(T), count);
    }
    /// Checks the checksum and that nothing follows it.
    void finish();
    /// Reads every block to the end and checks the checksum, without using them: what the
    /// header says is trusted only after this.
    void verify();

private:
    void block(void *data, size_t size, size_t count);
    void read(void *data, size_t bytes);
    std::string m_path, m_header;
    std::FILE *m_file = nullptr;
    uint64_t m_hash;
};

/// The header of the state file at `path` (the file's blocks are not read).
std::string read_state_header(const std::string &path);

} // namespace mvpt
