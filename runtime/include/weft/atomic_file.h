#pragma once
/// @file
/// Files written whole or not at all. The bytes go to a temporary file beside the target
/// (TARGET.partial), which replaces the target by one rename only after everything was written,
/// flushed and closed without error. A crash, a kill or a full disk leaves the previous file (or no
/// file) and at most the temporary one, never a target cut short.

#include <filesystem>
#include <fstream>
#include <string>

namespace weft {

class AtomicFile {
public:
    /// Opens the temporary file for writing (binary), after creating the target's folder when
    /// `make_folders`. Throws weft::Error naming the target when either fails (a missing folder too).
    explicit AtomicFile(std::filesystem::path target, bool make_folders = false);
    /// Not committed: the temporary file is removed; the target is as it was.
    ~AtomicFile();
    AtomicFile(AtomicFile&& other) noexcept;
    AtomicFile& operator=(AtomicFile&& other) noexcept;
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// Where to write: the temporary file's stream.
    [[nodiscard]] std::ofstream& stream() { return out_; }
    /// The temporary file's path, for writers that open files by name (libpng, TinyGLTF): close
    /// `stream()` first by calling `release_stream()`, write the file, then commit().
    [[nodiscard]] const std::filesystem::path& temporary() const { return temporary_; }
    void release_stream();
    /// Closes, checks and renames the temporary file onto the target. Throws weft::Error naming the
    /// target when a write failed (a full disk) or the rename did; the target is then untouched.
    void commit();

    [[nodiscard]] const std::filesystem::path& target() const { return target_; }

private:
    std::filesystem::path target_, temporary_;
    std::ofstream out_;
    bool committed_ = false;
};

/// Writes `bytes` to `target` through an AtomicFile. Throws as AtomicFile does.
void write_file_atomically(const std::filesystem::path& target, const std::string& bytes);

}  // namespace weft
