#include "render_state.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fcntl.h>
#include <unistd.h>

namespace mvpt {

namespace {
constexpr char Magic[8] = {'M', 'V', 'P', 'T', 'S', 'T', 'A', 'T'};
constexpr uint32_t FormatVersion = 4;
constexpr uint64_t MaxHeader = uint64_t(1) << 24;

/// A 64-bit checksum of a byte string, word by word, chained over blocks (corruption, not attacks).
uint64_t hash_bytes(uint64_t h, const void *data, size_t bytes) {
    const auto *p = static_cast<const unsigned char *>(data);
    auto mix = [](uint64_t h, uint64_t w) {
        h ^= w * 0x9E3779B97F4A7C15ull;
        return ((h << 29) | (h >> 35)) * 0xBF58476D1CE4E5B9ull;
    };
    size_t i = 0;
    for (; i + 8 <= bytes; i += 8) {
        uint64_t w;
        std::memcpy(&w, p + i, 8);
        h = mix(h, w);
    }
    uint64_t tail = 0;
    std::memcpy(&tail, p + i, bytes - i);
    return mix(mix(h, tail), bytes);
}

std::string errno_text() { return std::strerror(errno); }
} // namespace

StateWriter::StateWriter(const std::string &path, const std::string &header)
    : m_path(path), m_tmp(path + ".tmp"), m_hash(0) {
    m_file = std::fopen(m_tmp.c_str(), "wb");
    if (!m_file) throw std::runtime_error("cannot write the state file '" + m_tmp + "': " + errno_text());
    write(Magic, sizeof(Magic));
    write(&FormatVersion, sizeof(FormatVersion));
    const uint64_t n = header.size();
    write(&n, sizeof(n));
    write(header.data(), header.size());
    m_hash = hash_bytes(0, header.data(), header.size());
}

StateWriter::~StateWriter() {
    if (!m_file) return;
    std::fclose(m_file);
    std::remove(m_tmp.c_str());
}

void StateWriter::write(const void *data, size_t bytes) {
    if (bytes && std::fwrite(data, 1, bytes, m_file) != bytes)
        throw std::runtime_error("cannot write the state file '" + m_tmp + "': " + errno_text());
}

void StateWriter::block(const void *data, size_t size, size_t count) {
    const uint64_t n = count;
    const uint32_t s = uint32_t(size);
    write(&n, sizeof(n));
    write(&s, sizeof(s));
    write(data, size * count);
    m_hash = hash_bytes(hash_bytes(m_hash, &n, sizeof(n)), data, size * count);
}

void StateWriter::commit() {
    write(&m_hash, sizeof(m_hash));
    // The data on disk before the name points at it: a crash leaves the old state or the new.
    if (std::fflush(m_file) != 0 || ::fsync(fileno(m_file)) != 0)
        throw std::runtime_error("cannot write the state file '" + m_tmp + "': " + errno_text());
    const int closed = std::fclose(m_file);
    m_file = nullptr;
    if (closed != 0 || std::rename(m_tmp.c_str(), m_path.c_str()) != 0) {
        const std::string why = errno_text();
        std::remove(m_tmp.c_str());
        throw std::runtime_error("cannot write the state file '" + m_path + "': " + why);
    }
    const std::string dir = std::filesystem::path(m_path).parent_path().string();
    const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY);
    if (fd >= 0) ::fsync(fd), ::close(fd);
}

StateReader::StateReader(const std::string &path) : m_path(path), m_hash(0) {
    m_file = std::fopen(path.c_str(), "rb");
    if (!m_file) throw StateError("cannot read the state file '" + path + "': " + errno_text());
    char magic[sizeof(Magic)] = {};
    uint32_t version = 0;
    if (std::fread(magic, 1, sizeof(magic), m_file) != sizeof(magic) || std::memcmp(magic, Magic, sizeof(Magic)) != 0)
        throw StateError("'" + path + "' is not an mvpt state file");
    read(&version, sizeof(version));
    if (version != FormatVersion)
        throw StateError("the state file '" + path + "' has format " + std::to_string(version) + "; this mvpt reads format " +
                         std::to_string(FormatVersion));
    uint64_t n = 0;
    read(&n, sizeof(n));
    if (n > MaxHeader) throw StateError("the state file '" + path + "' is corrupt (a header of " + std::to_string(n) + " bytes)");
    m_header.resize(n);
    read(m_header.data(), n);
    m_hash = hash_bytes(0, m_header.data(), n);
}

StateReader::~StateReader() {
    if (m_file) std::fclose(m_file);
}

void StateReader::read(void *data, size_t bytes) {
    if (bytes && std::fread(data, 1, bytes, m_file) != bytes)
        throw StateError("the state file '" + m_path + "' is truncated");
}

void StateReader::block(void *data, size_t size, size_t count) {
    uint64_t n = 0;
    uint32_t s = 0;
    read(&n, sizeof(n));
    read(&s, sizeof(s));
    if (n != count || s != size)
        throw StateError("the state file '" + m_path + "' does not fit this render (a block of " + std::to_string(n) +
                         " values of " + std::to_string(s) + " bytes where " + std::to_string(count) + " of " +
                         std::to_string(size) + " were expected)");
    read(data, size * count);
    m_hash = hash_bytes(hash_bytes(m_hash, &n, sizeof(n)), data, size * count);
}

void StateReader::finish() {
    uint64_t stored = 0;
    read(&stored, sizeof(stored));
    if (stored != m_hash) throw StateError("the state file '" + m_path + "' is corrupt (its checksum does not match)");
    if (std::fgetc(m_file) != EOF) throw StateError("the state file '" + m_path + "' is corrupt (data after its end)");
}

void StateReader::verify() {
    const long start = std::ftell(m_file);
    if (start < 0 || std::fseek(m_file, 0, SEEK_END) != 0) throw StateError("cannot read the state file '" + m_path + "'");
    uint64_t left = uint64_t(std::ftell(m_file) - start);
    std::fseek(m_file, start, SEEK_SET);
    std::vector<unsigned char> data;
    while (left > sizeof(uint64_t)) {  // blocks of (count, size, count * size bytes), then the checksum
        uint64_t n = 0;
        uint32_t s = 0;
        if (left < sizeof(n) + sizeof(s) + sizeof(uint64_t))
            throw StateError("the state file '" + m_path + "' is corrupt (its blocks do not fill it)");
        read(&n, sizeof(n));
        read(&s, sizeof(s));
        left -= sizeof(n) + sizeof(s);
        if (s == 0 ? n != 0 : n > left / s) throw StateError("the state file '" + m_path + "' is truncated");
        data.resize(n * s);
        read(data.data(), data.size());
        left -= data.size();
        m_hash = hash_bytes(hash_bytes(m_hash, &n, sizeof(n)), data.data(), data.size());
    }
    finish();
}

std::string read_state_header(const std::string &path) {
    StateReader reader(path);
    reader.verify();
    return reader.header();
}

} // namespace mvpt
