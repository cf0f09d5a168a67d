// Byte records with a checksum, as Simulation::snapshot and the native unit's FMU state write them: a
// magic text, a version (uint32), the 64-bit FNV-1a checksum of the body (uint64), then the body: values in
// the machine's byte order (little-endian on every platform the units are built for), texts as their size
// (uint64) and bytes.
#pragma once
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace wc {

//: 64-bit FNV-1a of bytes.
inline std::uint64_t fnv1a(const unsigned char* data, std::size_t size) {
    std::uint64_t hash = 0xcbf29ce484222325ull;
    for (std::size_t i = 0; i < size; ++i) {
        hash ^= data[i];
        hash *= 0x100000001b3ull;
    }
    return hash;
}

//: Appends a record to `out`: begin() its header, put() and text() its body, seal() the checksum.
struct ByteWriter {
    std::vector<unsigned char>& out;
    std::size_t body = 0;  // where the body starts

    void begin(const char* magic, std::size_t magic_size, std::uint32_t version) {
        out.insert(out.end(), magic, magic + magic_size);
        put(version);
        put(std::uint64_t{0});  // the checksum, by seal()
        body = out.size();
    }
    template <class T>
    void put(const T& value) {
        const auto* p = reinterpret_cast<const unsigned char*>(&value);
        out.insert(out.end(), p, p + sizeof(T));
    }
    void put(const double* values, std::size_t count) {
        const auto* p = reinterpret_cast<const unsigned char*>(values);
        out.insert(out.end(), p, p + count * sizeof(double));
    }
    void text(const std::string& s) {
        put(static_cast<std::uint64_t>(s.size()));
        out.insert(out.end(), s.begin(), s.end());
    }
    void seal() {
        const std::uint64_t checksum = fnv1a(out.data() + body, out.size() - body);
        std::memcpy(out.data() + body - sizeof(checksum), &checksum, sizeof(checksum));
    }
};

//: Reads a record's values from `at` on; a read past its end throws Error(truncated).
template <class Error>
struct ByteReader {
    const unsigned char* data;
    std::size_t size, at;
    const char* truncated;

    template <class T>
    T get() {
        if (size - at < sizeof(T)) throw Error(truncated);
        T value;
        std::memcpy(&value, data + at, sizeof(T));
        at += sizeof(T);
        return value;
    }
    void get(double* values, std::size_t count) {
        if ((size - at) / sizeof(double) < count) throw Error(truncated);
        std::memcpy(values, data + at, count * sizeof(double));
        at += count * sizeof(double);
    }
    std::string text() {
        const auto length = get<std::uint64_t>();
        if (size - at < length) throw Error(truncated);
        std::string s(reinterpret_cast<const char*>(data + at), static_cast<std::size_t>(length));
        at += static_cast<std::size_t>(length);
        return s;
    }
    //: Whether the checksum just read matches the body (the bytes after it).
    bool body_matches(std::uint64_t checksum) const { return fnv1a(data + at, size - at) == checksum; }
};

}  // namespace wc
