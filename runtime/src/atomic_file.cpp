// Files written whole or not at all (weft/atomic_file.h).
#include "weft/atomic_file.h"

#include <system_error>
#include <utility>

#include "weft/error.h"

namespace weft {

AtomicFile::AtomicFile(std::filesystem::path target, bool make_folders) : target_(std::move(target)) {
    if (make_folders && target_.has_parent_path()) {
        std::error_code ec;
        std::filesystem::create_directories(target_.parent_path(), ec);
        if (ec) throw Error("cannot create the folder of '" + target_.string() + "': " + ec.message());
    }
    temporary_ = target_;
    temporary_ += ".partial";
    out_.open(temporary_, std::ios::binary | std::ios::trunc);
    if (!out_) throw Error("cannot open '" + target_.string() + "' for writing (its temporary '" + temporary_.string() + "')");
}

AtomicFile::~AtomicFile() {
    if (committed_ || temporary_.empty()) return;
    if (out_.is_open()) out_.close();
    std::error_code ec;
    std::filesystem::remove(temporary_, ec);
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : target_(std::move(other.target_)), temporary_(std::exchange(other.temporary_, {})), out_(std::move(other.out_)),
      committed_(other.committed_) {}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
    if (this != &other) {
        this->~AtomicFile();
        target_ = std::move(other.target_);
        temporary_ = std::exchange(other.temporary_, {});
        out_ = std::move(other.out_);
        committed_ = other.committed_;
    }
    return *this;
}

void AtomicFile::release_stream() {
    if (!out_.is_open()) return;
    out_.close();
    if (!out_) throw Error("failed writing '" + target_.string() + "' (disk full?)");
}

void AtomicFile::commit() {
    if (committed_) return;
    if (out_.is_open()) {
        out_.flush();
        out_.close();
        if (!out_) throw Error("failed writing '" + target_.string() + "' (disk full?); it was left as it was");
    }
    std::error_code ec;
    std::filesystem::rename(temporary_, target_, ec);
    if (ec) throw Error("cannot replace '" + target_.string() + "' by its finished copy: " + ec.message());
    committed_ = true;
}

void write_file_atomically(const std::filesystem::path& target, const std::string& bytes) {
    AtomicFile f(target);
    f.stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.commit();
}

}  // namespace weft
