#include "common/atomic_file.h"

#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <system_error>

#include <signal.h>
#include <unistd.h>

#include "common/input_error.h"

namespace shtool {
namespace {

[[noreturn]] void fail(const std::filesystem::path& target, const std::string& problem) {
  throw InputError("cannot write '" + target.string() + "': " + problem);
}

std::filesystem::path folder_of(const std::filesystem::path& target) {
  const std::filesystem::path dir = target.parent_path();
  return dir.empty() ? std::filesystem::path(".") : dir;
}

// Temporary files of this target left by a process that no longer runs (killed between
// writing and renaming): ".<name>.tmp-<pid>-<random>" whose pid is gone.
void remove_stale_temporaries(const std::filesystem::path& target) {
  std::string prefix(".");  // piece by piece: GCC 12's -Wrestrict false positive on "." + s
  prefix += target.filename().string();
  prefix += ".tmp-";
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder_of(target), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    char* end = nullptr;
    const long pid = std::strtol(name.c_str() + prefix.size(), &end, 10);
    if (pid <= 0 || !end || *end != '-') continue;
    if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      std::error_code rm;
      std::filesystem::remove(entry.path(), rm);
    }
  }
}

}  // namespace

PendingFile::PendingFile(std::filesystem::path target) : target_(std::move(target)) {
  check_output_path(target_, "");
  remove_stale_temporaries(target_);
  std::random_device rd;
  int open_errno = 0;
  for (int attempt = 0; attempt < 16 && !file_; ++attempt) {
    char suffix[64];
    std::snprintf(suffix, sizeof suffix, ".tmp-%ld-%08x%08x", static_cast<long>(::getpid()), rd(), rd());
    // Hidden and named after the target, so a leftover of a killed run is recognisable.
    // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "." + s.
    std::string name(".");
    name += target_.filename().string();
    name += suffix;
    const std::filesystem::path candidate = folder_of(target_) / name;
    // "x": exclusive creation, so two writers never share a temporary file.
    file_ = std::fopen(candidate.c_str(), "wbx");
    open_errno = errno;
    if (file_) temp_ = candidate;
    else if (open_errno != EEXIST) break;
  }
  if (!file_)
    fail(target_, "cannot create a temporary file in '" + folder_of(target_).string() + "': " +
                      std::strerror(open_errno));
}

PendingFile::PendingFile(PendingFile&& other) noexcept
    : target_(std::move(other.target_)), temp_(std::move(other.temp_)), file_(other.file_),
      committed_(other.committed_) {
  other.file_ = nullptr;
  other.temp_.clear();
}

PendingFile::~PendingFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !temp_.empty()) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

void PendingFile::write(std::string_view bytes) {
  if (!file_) fail(target_, "write after the file was finished");
  if (bytes.empty()) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) fail(target_, std::strerror(errno));
}

void PendingFile::write(std::span<const std::byte> bytes) {
  write(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

void PendingFile::finish() {
  if (!file_) return;
  const int flush_rc = std::fflush(file_);
  const int flush_errno = errno;
  const int close_rc = std::fclose(file_);
  const int close_errno = errno;
  file_ = nullptr;
  if (flush_rc != 0 || close_rc != 0) fail(target_, std::strerror(flush_rc != 0 ? flush_errno : close_errno));
}

void PendingFile::commit() {
  finish();
  std::error_code ec;
  std::filesystem::rename(temp_, target_, ec);
  if (ec) fail(target_, "cannot move the finished file into place: " + ec.message());
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& target, std::string_view bytes) {
  PendingFile f(target);
  f.write(bytes);
  f.commit();
}

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code ec;
  // Existing files by identity (hard links, symbolic links, other spellings) ...
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec))
    return std::filesystem::equivalent(a, b, ec);
  // ... and paths that do not exist yet by their normalised absolute form.
  const std::filesystem::path ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a, ec), ec);
  const std::filesystem::path cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b, ec), ec);
  return ca == cb;
}

void check_not_an_input(const std::filesystem::path& output, std::string_view what,
                        const std::filesystem::path& input) {
  if (!output.empty() && !input.empty() && same_file(output, input))
    throw InputError(std::string(what) + ": '" + output.string() + "' is the input '" + input.string() +
                     "'; refusing to overwrite it");
}

void write_files_atomically(std::span<const OutputFile> outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const bool same = same_file(outputs[i].path, outputs[j].path);
      if (same)
        throw InputError("two outputs are the same file: '" + outputs[j].path.string() + "' and '" +
                         outputs[i].path.string() + "'");
    }
  std::vector<PendingFile> pending;
  pending.reserve(outputs.size());
  for (const OutputFile& o : outputs) {
    pending.emplace_back(o.path);
    pending.back().write(o.bytes);
    pending.back().finish();
  }
  for (PendingFile& p : pending) p.commit();
}

void check_output_path(const std::filesystem::path& path, std::string_view what) {
  const std::string prefix = what.empty() ? std::string() : std::string(what) + ": ";
  if (path.empty()) throw InputError(prefix + "empty output path");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(prefix + "cannot write '" + path.string() + "': it is a folder, not a file");
  const std::filesystem::path dir = folder_of(path);
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(prefix + "cannot write '" + path.string() + "': folder '" + dir.string() + "' does not exist");
}

}  // namespace shtool
