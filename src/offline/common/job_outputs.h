// The output side of every job. A job declares its inputs and its outputs (each under the
// option that named it) before any work; each declaration is checked at once against all
// the others, so a long bake never starts when its result could not be written or would
// replace one of its own inputs. When the work is done the job hands over each output's
// bytes and commits: all or nothing.
//
//   JobOutputs io;
//   io.input(r.mesh, "the mesh");
//   io.output(r.out, "--out");
//   io.output(r.json, "--json");          // an empty path: not requested, ignored
//   ... work ...
//   io.set("--out", encode_table(t));
//   if (io.requested("--json")) io.set("--json", json);
//   io.commit();
//
// The commit writes and flushes every temporary file first (a full disk leaves nothing
// behind), keeps a link to each target's previous contents, then renames; if a rename
// fails, the targets already replaced get their previous contents back. SIGINT and
// SIGTERM wait for a commit under way to end (common/atomic_file.h removes the temporary
// files of one that has not started).
#pragma once

#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "common/atomic_file.h"

namespace shtool {

class JobOutputs {
 public:
  // A file the job reads; `what` names it in messages ("the mesh", "--fit"). Empty: ignored.
  void input(const std::filesystem::path& path, std::string what);
  // Several files of one input (a mesh's: the file and a glTF's buffers and images).
  void inputs(const std::vector<std::filesystem::path>& paths, const std::string& what);
  // An output under its option's name; empty: not requested. Throws InputError at once
  // when the path cannot be written (no folder, a folder), is one of the inputs (by real
  // path or hard link) or another output.
  void output(const std::filesystem::path& path, std::string option);
  // Several inputs or outputs at once, as (path, what or option) pairs, in order.
  using Named = std::pair<std::filesystem::path, std::string>;
  void input(std::initializer_list<Named> files);
  void output(std::initializer_list<Named> files);

  bool requested(std::string_view option) const;
  const std::filesystem::path& path(std::string_view option) const;

  // The bytes of a requested output (owned here until the commit).
  void set(std::string_view option, std::string bytes);
  // Or the output already written by the job into a PendingFile of path(option) (a big
  // one streamed piece by piece, PendingFile::write_at), renamed with the others.
  void set_written(std::string_view option, PendingFile file);

  // Every requested output must have its bytes. Throws InputError naming the output that
  // could not be written; then no output has changed.
  void commit() {
    stage();
    publish();
  }
  // commit() in its two steps: every temporary file written and flushed, then the renames
  // (a test puts an obstacle between them).
  void stage();
  void publish();

 private:
  struct Input {
    std::filesystem::path path;
    std::string what;
  };
  struct Output {
    std::filesystem::path path;
    std::string option;
    std::string bytes;
    bool set = false;
    std::optional<PendingFile> written;
  };
  Output& find(std::string_view option);
  const Output* find_if(std::string_view option) const;

  std::vector<Input> inputs_;
  std::vector<Output> outputs_;
  std::vector<PendingFile> pending_;  // between stage() and publish()
};

// Checks, before any work, that an output folder is one or can be made: nothing else of
// its name exists and its nearest existing ancestor is a folder (missing parents are
// made too, as `mkdir -p` does). InputError naming `option` otherwise.
void check_output_folder(const std::filesystem::path& dir, std::string_view option);

// Folders a job makes for its outputs, removed again (innermost first, and only when still
// empty) unless keep() is called after the commit: a job that fails, or that SIGINT or
// SIGTERM ends, leaves no folder.
class MadeFolders {
 public:
  // Makes `dir` and every missing parent. InputError naming `option` when one of them
  // exists and is not a folder, or cannot be made.
  void make(const std::filesystem::path& dir, const std::string& option);
  void keep();
  ~MadeFolders();

 private:
  std::vector<std::filesystem::path> made_;  // outermost first
  std::vector<int> slots_;                   // the signal handler's, one per folder
};

}  // namespace shtool
