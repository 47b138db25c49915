// A piece of work in a child process (core/child_process.hpp).
#include "core/child_process.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

enum class Status : int { ok = 0, input_error = 1, other_error = 2 };

bool write_all(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

// The child: runs the work, writes {status, message length, message, result length, result}.
[[noreturn]] void child(int fd, const std::function<std::string()>& work) {
  Status status = Status::ok;
  std::string message, result;
  try {
    result = work();
  } catch (const InputError& e) {
    status = Status::input_error;
    message = e.what();
  } catch (const std::exception& e) {
    status = Status::other_error;
    message = e.what();
  } catch (...) {
    status = Status::other_error;
    message = "unknown error";
  }
  const int code = static_cast<int>(status);
  const size_t len = message.size(), n = result.size();
  const bool ok = write_all(fd, &code, sizeof code) && write_all(fd, &len, sizeof len) &&
                  write_all(fd, message.data(), len) && write_all(fd, &n, sizeof n) && write_all(fd, result.data(), n);
  ::_exit(ok ? 0 : 1);
}

std::string read_all(int fd) {
  std::string data;
  char buf[1 << 16];
  for (;;) {
    const ssize_t r = ::read(fd, buf, sizeof buf);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    data.append(buf, static_cast<size_t>(r));
  }
  return data;
}

}  // namespace

std::string run_in_child(const std::function<std::string()>& work, const std::string& what,
                         const std::string& crash_hint) {
  int fds[2];
  if (::pipe(fds) != 0) throw NumericalError(what + ": cannot create a pipe: " + std::strerror(errno));
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw NumericalError(what + ": cannot start a child process: " + std::strerror(errno));
  }
  if (pid == 0) {
    ::close(fds[0]);
    child(fds[1], work);
  }
  ::close(fds[1]);
  const std::string data = read_all(fds[0]);
  ::close(fds[0]);
  int wstatus = 0;
  while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(wstatus))
    throw InputError(what + " crashed (signal " + std::to_string(WTERMSIG(wstatus)) + ")" + crash_hint);
  int code = 0;
  size_t len = 0, n = 0;
  const auto truncated = [&] { return NumericalError(what + ": the child process ended without a whole result"); };
  if (data.size() < sizeof code + sizeof len || !WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0) throw truncated();
  std::memcpy(&code, data.data(), sizeof code);
  std::memcpy(&len, data.data() + sizeof code, sizeof len);
  size_t at = sizeof code + sizeof len;
  if (data.size() < at + len + sizeof n) throw truncated();
  const std::string message = data.substr(at, len);
  at += len;
  std::memcpy(&n, data.data() + at, sizeof n);
  at += sizeof n;
  if (data.size() != at + n) throw truncated();
  if (code == static_cast<int>(Status::input_error)) throw InputError(message);
  if (code != static_cast<int>(Status::ok)) throw NumericalError(message);
  return data.substr(at, n);
}

}  // namespace vpm::detail
