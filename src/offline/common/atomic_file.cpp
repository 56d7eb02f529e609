#include "common/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <random>
#include <mutex>
#include <string>
#include <system_error>

#include <pthread.h>
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

// The temporary files and the folders made for outputs that exist now, for the signal
// handler: fixed slots of plain characters, since a handler may call unlink() and rmdir()
// but neither allocate nor lock. A slot is free (0), being filled (1) or live (2); a
// path beyond the last slot is still removed by its owner, only not on a signal.
constexpr int kSlots = 64;
char g_temp_paths[kSlots][PATH_MAX];
std::atomic<int> g_slot_state[kSlots];
std::atomic<bool> g_slot_is_folder[kSlots];
std::atomic<int> g_commits{0};           // CommitGuards alive
std::atomic<int> g_deferred_signal{0};   // a signal that came during a commit

void remove_registered_temporaries() {
  for (int i = 0; i < kSlots; ++i)
    if (g_slot_state[i].load() == 2 && !g_slot_is_folder[i].load()) ::unlink(g_temp_paths[i]);
  // Folders after the files in them, innermost first: a pass removes those already
  // empty, so as many passes as folders empty any chain of them (rmdir keeps a folder
  // that holds anything else).
  for (int pass = 0; pass < kSlots; ++pass) {
    bool removed = false;
    for (int i = 0; i < kSlots; ++i)
      if (g_slot_state[i].load() == 2 && g_slot_is_folder[i].load() && ::rmdir(g_temp_paths[i]) == 0) {
        g_slot_state[i].store(0);
        removed = true;
      }
    if (!removed) break;
  }
}

[[noreturn]] void end_as_signal(int sig) {
  remove_registered_temporaries();
  std::signal(sig, SIG_DFL);
  // Inside the handler the signal is blocked: unblocked, the raised one ends the process.
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, sig);
  std::raise(sig);
  ::pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
  std::_Exit(128 + sig);  // not reached
}

extern "C" void on_signal(int sig) {
  if (g_commits.load() > 0) {
    g_deferred_signal.store(sig);
    return;
  }
  end_as_signal(sig);
}

void install_signal_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (int sig : {SIGINT, SIGTERM}) {
      struct sigaction old {};
      if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;  // e.g. under nohup
      struct sigaction sa {};
      sa.sa_handler = on_signal;
      sigemptyset(&sa.sa_mask);
      ::sigaction(sig, &sa, nullptr);
    }
  });
}

int register_path(const std::filesystem::path& path, bool folder) {
  install_signal_handlers();
  const std::string& s = path.native();
  if (s.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (!g_slot_state[i].compare_exchange_strong(expected, 1)) continue;
    std::memcpy(g_temp_paths[i], s.c_str(), s.size() + 1);
    g_slot_is_folder[i].store(folder);
    g_slot_state[i].store(2);
    return i;
  }
  return -1;
}

int register_temporary(const std::filesystem::path& temp) { return register_path(temp, false); }

void unregister_temporary(int slot) {
  if (slot >= 0) g_slot_state[slot].store(0);
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

std::filesystem::path temporary_name_for(const std::filesystem::path& target) {
  static std::random_device rd;
  char suffix[64];
  std::snprintf(suffix, sizeof suffix, ".tmp-%ld-%08x%08x", static_cast<long>(::getpid()), rd(), rd());
  // Hidden and named after the target, so a leftover of a killed run is recognisable.
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "." + s.
  std::string name(".");
  name += target.filename().string();
  name += suffix;
  return folder_of(target) / name;
}

CommitGuard::CommitGuard() {
  install_signal_handlers();
  g_commits.fetch_add(1);
}

CommitGuard::~CommitGuard() {
  if (g_commits.fetch_sub(1) == 1) {
    const int sig = g_deferred_signal.exchange(0);
    if (sig != 0) end_as_signal(sig);
  }
}

namespace {
void check_output_place(const std::filesystem::path& path, std::string_view what);
}  // namespace

PendingFile::PendingFile(std::filesystem::path target) : target_(output_target(target)) {
  check_output_place(target_, "");
  remove_stale_temporaries(target_);
  int open_errno = 0;
  for (int attempt = 0; attempt < 16 && !file_; ++attempt) {
    const std::filesystem::path candidate = temporary_name_for(target_);
    // Registered before it exists, so a signal between the two cannot leave it behind.
    const int slot = register_temporary(candidate);
    // "x": exclusive creation, so two writers never share a temporary file.
    file_ = std::fopen(candidate.c_str(), "wbx");
    open_errno = errno;
    if (file_) {
      temp_ = candidate;
      slot_ = slot;
    } else {
      unregister_temporary(slot);
      if (open_errno != EEXIST) break;
    }
  }
  if (!file_)
    fail(target_, "cannot create a temporary file in '" + folder_of(target_).string() + "': " +
                      std::strerror(open_errno));
}

PendingFile::PendingFile(PendingFile&& other) noexcept
    : target_(std::move(other.target_)), temp_(std::move(other.temp_)), file_(other.file_),
      slot_(other.slot_), committed_(other.committed_) {
  other.file_ = nullptr;
  other.temp_.clear();
  other.slot_ = -1;
}

PendingFile::~PendingFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && !temp_.empty()) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
  unregister_temporary(slot_);
}

void PendingFile::write(std::string_view bytes) {
  if (!file_) fail(target_, "write after the file was finished");
  if (bytes.empty()) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) fail(target_, std::strerror(errno));
}

void PendingFile::write(std::span<const std::byte> bytes) {
  write(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

void PendingFile::write_at(std::uint64_t offset, std::string_view bytes) {
  if (!file_) fail(target_, "write after the file was finished");
  const int fd = ::fileno(file_);
  while (!bytes.empty()) {
    const ssize_t n = ::pwrite(fd, bytes.data(), bytes.size(), static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(target_, n < 0 ? std::strerror(errno) : "nothing written");
    bytes.remove_prefix(static_cast<std::size_t>(n));
    offset += static_cast<std::uint64_t>(n);
  }
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
  mark_committed();
}

void PendingFile::mark_committed() {
  committed_ = true;
  unregister_temporary(slot_);
  slot_ = -1;
}

void write_file_atomically(const std::filesystem::path& target, std::string_view bytes) {
  PendingFile f(target);
  f.write(bytes);
  f.finish();
  const CommitGuard guard;
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

namespace {

// check_output_path without the trial file, which is what PendingFile makes.
void check_output_place(const std::filesystem::path& path, std::string_view what) {
  const std::string prefix = what.empty() ? std::string() : std::string(what) + ": ";
  if (path.empty()) throw InputError(prefix + "empty output path");
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(st))
    throw InputError(prefix + "cannot write '" + path.string() + "': it is a folder, not a file");
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) {
    const char* kind = std::filesystem::is_fifo(st)             ? "a FIFO"
                       : std::filesystem::is_character_file(st) ? "a character device"
                       : std::filesystem::is_block_file(st)     ? "a block device"
                       : std::filesystem::is_socket(st)         ? "a socket"
                                                                : "not a regular file";
    throw InputError(prefix + "cannot write '" + path.string() + "': it is " + kind +
                     "; shtool writes each output whole to a temporary file and renames it into place, "
                     "which would replace it: give a file path");
  }
  const std::filesystem::path dir = folder_of(output_target(path));
  if (!std::filesystem::is_directory(dir, ec))
    throw InputError(prefix + "cannot write '" + path.string() + "': folder '" + dir.string() + "' does not exist");
}

}  // namespace

void check_output_path(const std::filesystem::path& path, std::string_view what) {
  check_output_place(path, what);
  // A folder that takes no new file (read-only, a full disk's inodes, /proc) fails here,
  // before the work, rather than at the commit: the same temporary file, made and removed.
  const std::string prefix = what.empty() ? std::string() : std::string(what) + ": ";
  try {
    const PendingFile probe(output_target(path));
  } catch (const InputError& e) {
    throw InputError(prefix + e.what());
  }
}

std::filesystem::path output_target(const std::filesystem::path& path) {
  // The kernel's own limit on links followed in one lookup (Linux's MAXSYMLINKS).
  constexpr int kMaxLinks = 40;
  std::filesystem::path p = path;
  for (int hops = 0; hops < kMaxLinks; ++hops) {
    std::error_code ec;
    if (!std::filesystem::is_symlink(std::filesystem::symlink_status(p, ec))) return p;
    const std::filesystem::path link = std::filesystem::read_symlink(p, ec);
    if (ec) return p;
    p = link.is_absolute() ? link : folder_of(p) / link;
  }
  throw InputError("cannot write '" + path.string() + "': more than " + std::to_string(kMaxLinks) +
                   " symbolic links to follow");
}

int register_made_folder(const std::filesystem::path& dir) { return register_path(dir, true); }

void forget_made_folder(int slot) { unregister_temporary(slot); }

}  // namespace shtool
