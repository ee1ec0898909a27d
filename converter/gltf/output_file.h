// Files written whole or not at all. An output goes to a temporary file beside it; every write is checked, the data
// flushed and synced, and only then is it renamed into place. On any failure (a full disk, an I/O error) the
// temporary is removed and nothing is left; with remove_temporary_files_on_signals, also on SIGINT and SIGTERM.
#pragma once

#include <memory>
#include <ostream>
#include <string>

#include "segmorph/status.h"

namespace segmorph {

class OutputFile {
 public:
  OutputFile();
  ~OutputFile();  // removes the temporary file unless committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Creates the temporary file for `path` (in path's directory, with the permissions a new file gets). "-" is the
  // standard output, written in place: its writes are checked, there is nothing to sync or rename.
  Status open(const std::string& path);
  // Where to write; a failed write is remembered and reported by finish().
  std::ostream& stream();
  // Flushes, checks that every write succeeded, syncs and closes the temporary file.
  Status finish();
  // Renames the finished temporary file to the path.
  Status commit();
  // Renames `first`, then `second` (both finished), with SIGINT and SIGTERM held in between: a signal finds both
  // in place or neither.
  static Status commit(OutputFile& first, OutputFile& second);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Writes `size` bytes to `path` through an OutputFile.
Status save_file(const std::string& path, const void* data, size_t size);

// Installs handlers of SIGINT and SIGTERM that remove the temporary files of the OutputFiles open at the time, then
// end the process as the signal would have (a command-line tool's choice; a library leaves signals to its host).
void remove_temporary_files_on_signals();

// Whether `a` and `b` name the same existing file (through links too).
bool same_file(const std::string& a, const std::string& b);

}  // namespace segmorph
