#include "gltf/output_file.h"

#include <fcntl.h>
#include <pthread.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <streambuf>

namespace segmorph {
namespace {

// The temporary files open now, for the signal handlers: fixed slots of fixed size, so that the handler only reads
// memory that is always there and calls only unlink (async-signal-safe).
constexpr int kSlots = 16;
constexpr size_t kSlotBytes = 4096;
char slot_paths[kSlots][kSlotBytes];
// 0: free; 1: taken, its path being written; 2: its path is there (the handler removes only these).
std::atomic<int> slot_state[kSlots];

int take_slot(const std::string& path) {
  if (path.size() >= kSlotBytes) return -1;
  for (int s = 0; s < kSlots; ++s) {
    int expected = 0;
    if (!slot_state[s].compare_exchange_strong(expected, 1)) continue;
    std::memcpy(slot_paths[s], path.c_str(), path.size() + 1);
    slot_state[s].store(2);
    return s;
  }
  return -1;  // more open at once than slots: still written safely, only not removed on a signal
}

void release_slot(int s) {
  if (s >= 0) slot_state[s].store(0);
}

// Holds SIGINT and SIGTERM for its lifetime.
class HeldSignals {
 public:
  HeldSignals() {
    sigset_t held;
    sigemptyset(&held);
    sigaddset(&held, SIGINT);
    sigaddset(&held, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &held, &before_);
  }
  ~HeldSignals() { pthread_sigmask(SIG_SETMASK, &before_, nullptr); }

 private:
  sigset_t before_;
};

extern "C" void remove_temporaries_and_end(int signal_number) {
  for (int s = 0; s < kSlots; ++s)
    if (slot_state[s].load() == 2) unlink(slot_paths[s]);
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

// A streambuf over a file descriptor that remembers the first failed write.
class DescriptorBuffer : public std::streambuf {
 public:
  explicit DescriptorBuffer(int descriptor) : descriptor_(descriptor) { setp(buffer_, buffer_ + sizeof(buffer_)); }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* data, std::streamsize size) override {
    if (size < std::streamsize(sizeof(buffer_))) return std::streambuf::xsputn(data, size);
    return drain() && write_all(data, size_t(size)) ? size : 0;  // large blocks go straight through
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const size_t pending = size_t(pptr() - pbase());
    setp(buffer_, buffer_ + sizeof(buffer_));
    return write_all(buffer_, pending);
  }
  bool write_all(const char* data, size_t size) {
    if (error_) return false;
    while (size > 0) {
      const ssize_t written = write(descriptor_, data, size);
      if (written < 0 && errno == EINTR) continue;
      if (written <= 0) {
        error_ = written < 0 ? errno : EIO;
        return false;
      }
      data += written, size -= size_t(written);
    }
    return true;
  }

  int descriptor_;
  int error_ = 0;
  char buffer_[1 << 16];
};

}  // namespace

struct OutputFile::State {
  std::string path, temporary;
  int descriptor = -1;
  int slot = -1;
  bool committed = false;
  bool standard_output = false;  // "-": written in place, nothing to rename or remove
  std::unique_ptr<DescriptorBuffer> buffer;
  std::unique_ptr<std::ostream> stream;
};

OutputFile::OutputFile() : state_(new State) {}

OutputFile::~OutputFile() {
  if (state_->standard_output) return;
  if (state_->descriptor >= 0) close(state_->descriptor);
  if (!state_->temporary.empty() && !state_->committed) unlink(state_->temporary.c_str());
  release_slot(state_->slot);
}

Status OutputFile::open(const std::string& path) {
  State& s = *state_;
  s.path = path;
  if (path == "-") {
    s.path = "the standard output";
    s.standard_output = true;
    s.descriptor = STDOUT_FILENO;
    s.buffer.reset(new DescriptorBuffer(s.descriptor));
    s.stream.reset(new std::ostream(s.buffer.get()));
    return Status::Ok();
  }
  const size_t slash = path.find_last_of('/');
  const std::string directory = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  std::string temporary = directory + "." + name + ".segmorph-XXXXXX";
  // The signals are held while the file is created and its name recorded: a handler sees no half-written name,
  // and no file exists that it does not know of.
  int error = 0;
  {
    HeldSignals held;
    s.descriptor = mkstemp(&temporary[0]);
    error = errno;
    if (s.descriptor >= 0) s.slot = take_slot(temporary);
  }
  if (s.descriptor < 0) return Status(StatusCode::io_error, "cannot write " + path + ": " + std::strerror(error));
  s.temporary = temporary;
  // mkstemp makes the file private; the output gets the permissions any new file would.
  const mode_t mask = umask(0);
  umask(mask);
  fchmod(s.descriptor, 0666 & ~mask);
  s.buffer.reset(new DescriptorBuffer(s.descriptor));
  s.stream.reset(new std::ostream(s.buffer.get()));
  return Status::Ok();
}

std::ostream& OutputFile::stream() { return *state_->stream; }

Status OutputFile::finish() {
  State& s = *state_;
  s.stream->flush();
  int error = s.buffer->error();
  if (!error && !*s.stream) error = EIO;
  if (s.standard_output) {  // a pipe or a terminal: nothing to sync, and the descriptor stays open
    if (error) return Status(StatusCode::io_error, "cannot write " + s.path + ": " + std::strerror(error));
    return Status::Ok();
  }
  if (!error && fsync(s.descriptor) != 0) error = errno;
  if (close(s.descriptor) != 0 && !error) error = errno;
  s.descriptor = -1;
  if (error) return Status(StatusCode::io_error, "cannot write " + s.path + ": " + std::strerror(error));
  return Status::Ok();
}

Status OutputFile::commit() {
  State& s = *state_;
  if (s.standard_output) return s.committed = true, Status::Ok();
  if (std::rename(s.temporary.c_str(), s.path.c_str()) != 0)
    return Status(StatusCode::io_error, "cannot write " + s.path + ": " + std::strerror(errno));
  s.committed = true;
  release_slot(s.slot), s.slot = -1;
  return Status::Ok();
}

Status OutputFile::commit(OutputFile& first, OutputFile& second) {
  HeldSignals held;
  SEGMORPH_RETURN_IF_ERROR(first.commit());
  return second.commit();
}

Status save_file(const std::string& path, const void* data, size_t size) {
  OutputFile file;
  SEGMORPH_RETURN_IF_ERROR(file.open(path));
  file.stream().write(static_cast<const char*>(data), std::streamsize(size));
  SEGMORPH_RETURN_IF_ERROR(file.finish());
  return file.commit();
}

void remove_temporary_files_on_signals() {
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_handler = remove_temporaries_and_end;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  return stat(a.c_str(), &sa) == 0 && stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

}  // namespace segmorph
