// Output files written in full or not at all. Every file the offline tool writes goes
// through here: the bytes go to an exclusive, hidden temporary file in the target's
// folder (".<name>.tmp-<pid>-<random>"), flushed and closed, then renamed over the
// target. On any failure, including an exception unwinding past a PendingFile, the
// temporary file is removed and an old file at the target stays untouched; temporary
// files of the target whose process is gone (killed between write and rename) are
// removed by the next write, and SIGINT or SIGTERM removes the temporary files of this
// process before ending it as the signal would.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string_view>

namespace shtool {

// One output being written. Create it, write(), then commit(); destroyed without
// commit() it removes its temporary file. Throws InputError naming the target.
class PendingFile {
 public:
  explicit PendingFile(std::filesystem::path target);
  ~PendingFile();
  PendingFile(PendingFile&& other) noexcept;
  PendingFile& operator=(PendingFile&&) = delete;
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;

  void write(std::string_view bytes);
  void write(std::span<const std::byte> bytes);
  // The bytes at a byte offset of the file, unbuffered (one pwrite): several threads may
  // write disjoint pieces of one big output at once, in any order. Not to be mixed with
  // write() on the same file.
  void write_at(std::uint64_t offset, std::string_view bytes);
  // Flushes and closes the temporary file (reporting a full disk here, not later).
  void finish();
  // finish() if needed, then renames the temporary file over the target.
  void commit();

  const std::filesystem::path& target() const { return target_; }
  const std::filesystem::path& temporary() const { return temp_; }
  // After the caller moved the finished temporary file into place itself.
  void mark_committed();

 private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::FILE* file_ = nullptr;
  int slot_ = -1;  // in the signal handler's list
  bool committed_ = false;
};

// The one-output case of JobOutputs (common/job_outputs.h), for writers that are not jobs.
void write_file_atomically(const std::filesystem::path& target, std::string_view bytes);

// While a CommitGuard lives, SIGINT and SIGTERM are held back; when it ends, a signal
// that came meanwhile ends the process as it would have. A commit that renames several
// files is thereby never cut in half by a signal.
class CommitGuard {
 public:
  CommitGuard();
  ~CommitGuard();
  CommitGuard(const CommitGuard&) = delete;
  CommitGuard& operator=(const CommitGuard&) = delete;
};

// A folder just made for outputs, removed (when empty) if SIGINT or SIGTERM ends the
// process before forget_made_folder(slot); returns its slot (-1: none free, then only
// its owner removes it). For MadeFolders (common/job_outputs.h).
int register_made_folder(const std::filesystem::path& dir);
void forget_made_folder(int slot);

// A name for a hidden file beside `target` that the next write removes if this process
// is gone (".<name>.tmp-<pid>-<random>").
std::filesystem::path temporary_name_for(const std::filesystem::path& target);

// Whether two paths name one file: existing files by identity (links, other spellings),
// others by their normalised absolute paths.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

// Checks, before any work, that `path` can be written: its folder exists and is a
// folder, and the path (its symbolic links followed) is a regular file or nothing: not
// a folder, and not a FIFO, device or socket, which the rename into place would replace
// instead of writing to; and that its folder takes a new file (one is made and removed).
// `what` names the option in the message ("--out"; empty: no prefix).
void check_output_path(const std::filesystem::path& path, std::string_view what);

// The file a write to `path` replaces: `path` with its own symbolic links followed (a
// link that names a file is written through, as `cp` does, rather than replaced by a
// file); other paths as given.
std::filesystem::path output_target(const std::filesystem::path& path);

}  // namespace shtool
