#include "hopper/campaign/checkpoints.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>

#include "hopper/core/error.hpp"

namespace hopper::campaign {

namespace fs = std::filesystem;

namespace {

constexpr char magic[] = "HOPPERCK";
constexpr std::uint32_t file_version = 1;

[[noreturn]] void fail_errno(const std::string& what, const fs::path& p) {
    throw core::StoreError(what + " " + p.string() + ": " + std::strerror(errno));
}

void write_all(int fd, const std::uint8_t* p, std::size_t n, const fs::path& path) {
    while (n > 0) {
        const ssize_t k = ::write(fd, p, n);
        if (k < 0) {
            if (errno == EINTR) continue;
            const int e = errno;
            ::close(fd);
            ::unlink(path.c_str());
            errno = e;
            fail_errno("cannot write the checkpoint", path);
        }
        p += k;
        n -= static_cast<std::size_t>(k);
    }
}

void sync_dir(const fs::path& dir) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
    if (fd < 0) return;  // best effort
    ::fsync(fd);
    ::close(fd);
}

std::string hex(std::uint64_t v) {
    char b[17];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
    return b;
}

}  // namespace

CheckpointFiles::CheckpointFiles(fs::path store, std::string code_version)
    : dir_(dir_for(store)), code_version_(std::move(code_version)) {}

fs::path CheckpointFiles::dir_for(const fs::path& store) {
    fs::path d = store;
    d += ".checkpoints";
    return d;
}

fs::path CheckpointFiles::path_of(const CheckpointKey& k) const {
    // The label may hold any characters: the file is named by its hash and the index.
    return dir_ / (hex(store::fnv1a64(k.label)) + "-" + std::to_string(k.realization) + ".ckpt");
}

void CheckpointFiles::write(const CheckpointKey& k, double worker_seconds,
                            std::span<const std::uint8_t> state) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    if (ec)
        throw core::StoreError("cannot create the checkpoint directory " + dir_.string() + ": " +
                               ec.message());
    store::ByteWriter w;
    for (const char* c = magic; *c; ++c)
        w.u8(static_cast<std::uint8_t>(*c));
    w.u32(file_version);
    w.str(code_version_);
    w.str(k.label);
    w.u64(k.physics);
    w.i32(k.realization);
    w.u64(k.seed);
    w.f64(worker_seconds);
    w.u64(state.size());
    store::Bytes b = w.take();
    b.insert(b.end(), state.begin(), state.end());
    const std::uint32_t crc = store::crc32c(b);
    for (int i = 0; i < 4; ++i)
        b.push_back(static_cast<std::uint8_t>(crc >> (8 * i)));

    const fs::path final_path = path_of(k);
    fs::path tmp = final_path;
    tmp += ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) fail_errno("cannot create the checkpoint", tmp);
    write_all(fd, b.data(), b.size(), tmp);
    if (::fsync(fd) != 0) {
        const int e = errno;
        ::close(fd);
        ::unlink(tmp.c_str());
        errno = e;
        fail_errno("cannot sync the checkpoint", tmp);
    }
    ::close(fd);
    if (::rename(tmp.c_str(), final_path.c_str()) != 0) {
        const int e = errno;
        ::unlink(tmp.c_str());
        errno = e;
        fail_errno("cannot rename the checkpoint into place:", final_path);
    }
    sync_dir(dir_);
}

std::optional<LoadedCheckpoint> CheckpointFiles::read(const CheckpointKey& k,
                                                      std::string* refusal) {
    const fs::path p = path_of(k);
    std::ifstream in(p, std::ios::binary);
    if (!in) return std::nullopt;
    const store::Bytes b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto refuse = [&](const std::string& why) -> std::optional<LoadedCheckpoint> {
        if (refusal)
            *refusal = "checkpoint " + p.string() + " of '" + k.label + "' #" +
                       std::to_string(k.realization) + " refused: " + why +
                       "; removed, the realization restarts from its beginning";
        remove(k);
        return std::nullopt;
    };
    try {
        if (b.size() < 12 || std::memcmp(b.data(), magic, 8) != 0)
            return refuse("not a hopper checkpoint file");
        std::uint32_t crc = 0;
        for (int i = 0; i < 4; ++i)
            crc |= std::uint32_t(b[b.size() - 4 + std::size_t(i)]) << (8 * i);
        const std::span<const std::uint8_t> body(b.data(), b.size() - 4);
        if (store::crc32c(body) != crc) return refuse("damaged (its checksum does not match)");
        store::ByteReader r(body.subspan(8), "checkpoint " + p.string());
        const std::uint32_t version = r.u32();
        if (version != file_version)
            return refuse("file format " + std::to_string(version) + ", this code reads " +
                          std::to_string(file_version));
        const std::string code = r.str();
        if (code != code_version_)
            return refuse("written by code version " + code + ", this is " + code_version_ +
                          " (a state is only continued by the code that wrote it)");
        const std::string label = r.str();
        const std::uint64_t physics = r.u64();
        const int realization = r.i32();
        const std::uint64_t seed = r.u64();
        if (label != k.label || realization != k.realization)
            return refuse("it belongs to '" + label + "' #" + std::to_string(realization));
        if (physics != k.physics)
            return refuse("it was written for other physics of this point (physics hash " +
                          hex(physics) + ", now " + hex(k.physics) + ")");
        if (seed != k.seed)
            return refuse("seed " + std::to_string(seed) + ", expected " + std::to_string(k.seed));
        LoadedCheckpoint out;
        out.worker_seconds = r.f64();
        const std::uint64_t n = r.u64();
        if (n != r.remaining()) return refuse("its state has the wrong length");
        const std::size_t at = b.size() - 4 - n;
        out.state.assign(b.begin() + static_cast<std::ptrdiff_t>(at), b.end() - 4);
        return out;
    } catch (const core::StoreError& e) {
        return refuse(std::string("unreadable (") + e.what() + ")");
    }
}

std::optional<double> CheckpointFiles::peek_seconds(const CheckpointKey& k) const {
    std::ifstream in(path_of(k), std::ios::binary);
    if (!in) return std::nullopt;
    store::Bytes b(4096);
    in.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(b.size()));
    b.resize(static_cast<std::size_t>(in.gcount()));
    try {
        if (b.size() < 12 || std::memcmp(b.data(), magic, 8) != 0) return std::nullopt;
        store::ByteReader r(std::span<const std::uint8_t>(b).subspan(8), "checkpoint header");
        if (r.u32() != file_version) return std::nullopt;
        r.str();
        if (r.str() != k.label) return std::nullopt;
        r.u64();
        r.i32();
        r.u64();
        return r.f64();
    } catch (const core::StoreError&) {
        return std::nullopt;
    }
}

void CheckpointFiles::remove(const CheckpointKey& k) {
    std::error_code ec;
    fs::remove(path_of(k), ec);
    fs::path tmp = path_of(k);
    tmp += ".tmp";
    fs::remove(tmp, ec);
}

void CheckpointFiles::remove_dir_if_empty() {
    std::error_code ec;
    if (fs::is_directory(dir_, ec) && fs::is_empty(dir_, ec)) fs::remove(dir_, ec);
}

int CheckpointFiles::count() const {
    std::error_code ec;
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir_, ec))
        if (e.path().extension() == ".ckpt") ++n;
    return n;
}

}  // namespace hopper::campaign
