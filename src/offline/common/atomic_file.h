// Output files written in full or not at all. Every file the offline tool writes goes
// through here: the bytes go to an exclusive, hidden temporary file in the target's
// folder (".<name>.tmp-<pid>-<random>"), flushed and closed, then renamed over the
// target. On any failure, including an exception unwinding past a PendingFile, the
// temporary file is removed and an old file at the target stays untouched; temporary
// files of the target whose process is gone (killed between write and rename) are
// removed by the next write.
#pragma once

#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

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
  // Flushes and closes the temporary file (reporting a full disk here, not later).
  void finish();
  // finish() if needed, then renames the temporary file over the target.
  void commit();

  const std::filesystem::path& target() const { return target_; }

 private:
  std::filesystem::path target_;
  std::filesystem::path temp_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

// The one-output case.
void write_file_atomically(const std::filesystem::path& target, std::string_view bytes);

// One output of a command that writes several.
struct OutputFile {
  std::filesystem::path path;
  std::string_view bytes;
};

// All or none: every temporary file is written and flushed before the first rename, so
// a full disk or a missing folder leaves none of the outputs behind. Refuses two outputs
// that are the same file.
void write_files_atomically(std::span<const OutputFile> outputs);

// Whether two paths name one file: existing files by identity (links, other spellings),
// others by their normalised absolute paths.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

// Refuses an output that is the command's input (InputError naming both); `what` names
// the output's option.
void check_not_an_input(const std::filesystem::path& output, std::string_view what,
                        const std::filesystem::path& input);

// Checks, before any work, that `path` can be written: its folder exists and is a
// folder, and the path itself is not a folder. `what` names the option in the message
// ("--out"; empty: no prefix).
void check_output_path(const std::filesystem::path& path, std::string_view what);

}  // namespace shtool
