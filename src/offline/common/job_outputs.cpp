#include "common/job_outputs.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include <unistd.h>

#include "common/input_error.h"

namespace shtool {
namespace {

// Piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "'" + s.
std::string quoted(const std::filesystem::path& p) {
  std::string q(1, '\'');
  q += p.string();
  q += '\'';
  return q;
}

}  // namespace

void JobOutputs::input(const std::filesystem::path& path, std::string what) {
  if (path.empty()) return;
  for (const Output& o : outputs_)
    if (same_file(o.path, path))
      throw InputError(o.option + ": " + quoted(o.path) + " is the input " + quoted(path) + " (" + what +
                       "); refusing to overwrite it");
  inputs_.push_back({path, std::move(what)});
}

void JobOutputs::inputs(const std::vector<std::filesystem::path>& paths, const std::string& what) {
  for (const std::filesystem::path& p : paths) input(p, what);
}

void JobOutputs::input(std::initializer_list<Named> files) {
  for (const Named& f : files) input(f.first, f.second);
}

void JobOutputs::output(std::initializer_list<Named> files) {
  for (const Named& f : files) output(f.first, f.second);
}

void JobOutputs::output(const std::filesystem::path& path, std::string option) {
  if (path.empty()) return;
  if (find_if(option)) throw std::logic_error("output " + option + " declared twice");
  check_output_path(path, option);
  // The path a link names, so that the rename writes through the link; compared as that,
  // since a link to a file not yet there names no file for same_file to identify.
  const std::filesystem::path target = output_target(path);
  for (const Input& i : inputs_)
    if (same_file(path, i.path) || same_file(target, i.path))
      throw InputError(option + ": " + quoted(path) + " is the input " + quoted(i.path) + " (" + i.what +
                       "); refusing to overwrite it");
  for (const Output& o : outputs_)
    if (same_file(target, o.path))
      throw InputError(option + " and " + o.option + " name the same file " + quoted(path));
  outputs_.push_back({target, std::move(option), {}, false, std::nullopt});
}

const JobOutputs::Output* JobOutputs::find_if(std::string_view option) const {
  for (const Output& o : outputs_)
    if (o.option == option) return &o;
  return nullptr;
}

JobOutputs::Output& JobOutputs::find(std::string_view option) {
  for (Output& o : outputs_)
    if (o.option == option) return o;
  throw std::logic_error("output " + std::string(option) + " was not requested");
}

bool JobOutputs::requested(std::string_view option) const { return find_if(option) != nullptr; }

const std::filesystem::path& JobOutputs::path(std::string_view option) const {
  const Output* o = find_if(option);
  if (!o) throw std::logic_error("output " + std::string(option) + " was not requested");
  return o->path;
}

void JobOutputs::set(std::string_view option, std::string bytes) {
  Output& o = find(option);
  o.bytes = std::move(bytes);
  o.set = true;
}

void JobOutputs::set_written(std::string_view option, PendingFile file) {
  Output& o = find(option);
  if (file.target() != o.path) throw std::logic_error("output " + o.option + " written to another path");
  o.written.emplace(std::move(file));
  o.bytes = std::string();
  o.set = true;
}

void JobOutputs::stage() {
  for (const Output& o : outputs_)
    if (!o.set) throw std::logic_error("output " + o.option + " has no bytes");
  // Every temporary file written and flushed: a full disk stops here, nothing replaced.
  pending_.clear();
  pending_.reserve(outputs_.size());
  for (Output& o : outputs_) {
    try {
      if (o.written) {
        pending_.emplace_back(std::move(*o.written));
        o.written.reset();
        pending_.back().finish();
        continue;
      }
      pending_.emplace_back(o.path);
      pending_.back().write(o.bytes);
      pending_.back().finish();
      o.bytes = std::string();  // written: its memory goes back
    } catch (const InputError& e) {
      throw InputError(o.option + ": " + e.what());
    }
  }
}

void JobOutputs::publish() {
  std::vector<PendingFile> pending = std::move(pending_);
  pending_.clear();
  if (pending.size() != outputs_.size()) throw std::logic_error("JobOutputs::publish before stage");
  // Each target's previous contents kept under a second name (a hard link, no copy),
  // then the renames; a failed rename puts back what the earlier ones replaced.
  const CommitGuard guard;
  struct Kept {
    std::filesystem::path backup;  // empty: the target did not exist
  };
  std::vector<Kept> kept(outputs_.size());
  auto remove_backups = [&] {
    for (const Kept& k : kept)
      if (!k.backup.empty()) ::unlink(k.backup.c_str());
  };
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    const std::filesystem::path& target = outputs_[i].path;
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::symlink_status(target, ec);
    // A folder that took the target's place since the checks cannot be replaced: its
    // rename below fails and undoes the others.
    if (std::filesystem::exists(st) && !std::filesystem::is_directory(st)) {
      const std::filesystem::path backup = temporary_name_for(target);
      if (::link(target.c_str(), backup.c_str()) == 0) kept[i].backup = backup;
      else {
        const int err = errno;
        remove_backups();
        throw InputError(outputs_[i].option + ": cannot write " + quoted(target) +
                         ": cannot keep its previous contents while the outputs are replaced: " + std::strerror(err));
      }
    }
  }
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    std::error_code ec;
    std::filesystem::rename(pending[i].temporary(), outputs_[i].path, ec);
    if (!ec) {
      pending[i].mark_committed();
      continue;
    }
    // Back to the state before the commit: the replaced targets get their contents
    // back, the created ones go.
    for (std::size_t j = 0; j < i; ++j) {
      if (!kept[j].backup.empty()) {
        std::error_code rc;
        std::filesystem::rename(kept[j].backup, outputs_[j].path, rc);
        if (!rc) kept[j].backup.clear();
      } else {
        ::unlink(outputs_[j].path.c_str());
      }
    }
    remove_backups();
    throw InputError(outputs_[i].option + ": cannot move the finished file into place at " + quoted(outputs_[i].path) +
                     ": " + ec.message() + "; no output was changed");
  }
  remove_backups();
}

void check_output_folder(const std::filesystem::path& dir, std::string_view option) {
  const std::string prefix = std::string(option) + " " + dir.string() + ": ";
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) return;
  if (std::filesystem::exists(dir, ec)) throw InputError(prefix + "exists and is not a folder");
  const std::filesystem::path absolute = std::filesystem::absolute(dir, ec);
  for (std::filesystem::path p = absolute.parent_path(); !p.empty(); p = p.parent_path()) {
    if (std::filesystem::is_directory(p, ec)) return;
    if (std::filesystem::exists(p, ec)) throw InputError(prefix + "cannot be made: " + p.string() + " is not a folder");
    if (p == p.parent_path()) break;
  }
}

void MadeFolders::make(const std::filesystem::path& dir, const std::string& option) {
  std::error_code ec;
  if (std::filesystem::is_directory(dir, ec)) return;
  if (std::filesystem::exists(dir, ec))
    throw InputError(option + " " + dir.string() + ": exists and is not a folder");
  const std::filesystem::path parent = dir.parent_path();
  if (!parent.empty() && parent != dir) make(parent, option);
  if (!std::filesystem::create_directory(dir, ec) || ec)
    throw InputError(option + ": cannot create the folder " + dir.string() + ": " +
                     (ec ? ec.message() : std::string("unknown error")));
  made_.push_back(dir);
  slots_.push_back(register_made_folder(dir));
}

void MadeFolders::keep() {
  for (int slot : slots_) forget_made_folder(slot);
  slots_.clear();
  made_.clear();
}

MadeFolders::~MadeFolders() {
  for (auto it = made_.rbegin(); it != made_.rend(); ++it) {
    std::error_code ec;
    std::filesystem::remove(*it, ec);  // only an empty one
  }
  for (int slot : slots_) forget_made_folder(slot);
}

}  // namespace shtool
