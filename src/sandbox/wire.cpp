// The keeper's wire: encoding, and both ends' sending and receiving (see wire.hpp). The
// keeper's end is async-signal-safe only.

#include "wire.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace overtake::sandbox::wire {
namespace {

void put_int(char* at, int v) {
  std::memcpy(at, &v, sizeof v);
}
int get_int(const char* at) {
  int v = 0;
  std::memcpy(&v, at, sizeof v);
  return v;
}

// Requests: kind, sequence, argument.
void encode_request(char* buf, char kind, unsigned sequence, int arg) {
  buf[0] = kind;
  put_int(buf + 1, static_cast<int>(sequence));
  put_int(buf + 1 + sizeof(int), arg);
}
Message decode_request(const char* buf) {
  Message m;
  m.kind = buf[0];
  m.sequence = static_cast<unsigned>(get_int(buf + 1));
  m.a = get_int(buf + 1 + sizeof(int));
  return m;
}

// Answers: kind, sequence, two numbers.
void encode_answer(char* buf, char kind, unsigned sequence, int a, int b) {
  buf[0] = kind;
  put_int(buf + 1, static_cast<int>(sequence));
  put_int(buf + 1 + sizeof(int), a);
  put_int(buf + 1 + 2 * sizeof(int), b);
}
Message decode_answer(const char* buf) {
  Message m;
  m.kind = buf[0];
  m.sequence = static_cast<unsigned>(get_int(buf + 1));
  m.a = get_int(buf + 1 + sizeof(int));
  m.b = get_int(buf + 1 + 2 * sizeof(int));
  return m;
}

// A message of one buffer with room for one descriptor beside it.
struct FdMessage {
  iovec iov{};
  alignas(cmsghdr) char space[CMSG_SPACE(sizeof(int))] = {};
  msghdr msg{};
  FdMessage(void* data, std::size_t size) : iov{data, size} {
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = space;
    msg.msg_controllen = sizeof space;
  }
  FdMessage(const FdMessage&) = delete;
  FdMessage& operator=(const FdMessage&) = delete;
};

// Waits until `control` has something to read, within `timeout`.
bool wait_readable(int control, std::chrono::milliseconds timeout) {
  pollfd pfd{control, POLLIN, 0};
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    const int r = ::poll(&pfd, 1, static_cast<int>(left.count()));
    if (r > 0) return true;
    if (r < 0 && errno != EINTR) return false;
  }
}

// The descriptor a received message carries, to `*fd` (closed when `fd` is null).
void take_fd(msghdr& msg, int* fd) {
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) {
      int got = -1;
      std::memcpy(&got, CMSG_DATA(c), sizeof got);
      if (fd)
        *fd = got;
      else
        ::close(got);
    }
  }
}

// Receives one answer (and a descriptor, when one came with it) within `timeout`.
bool receive(int control, Message& m, int* fd, std::chrono::milliseconds timeout) {
  if (!wait_readable(control, timeout)) return false;
  char buf[kAnswerSize] = {};
  FdMessage fm(buf, sizeof buf);
  msghdr& msg = fm.msg;
  const ssize_t n = ::recvmsg(control, &msg, MSG_CMSG_CLOEXEC);
  if (n <= 0) return false;
  m = decode_answer(buf);
  take_fd(msg, fd);
  return true;
}

}  // namespace

// ---- the keeper's end (async-signal-safe) -------------------------------------------------------

ssize_t receive_request(int control, Message& m) {
  char buf[kRequestSize] = {};
  const ssize_t n = ::recv(control, buf, sizeof buf, 0);
  if (n > 0) m = decode_request(buf);
  return n;
}

void send_answer(int control, char kind, unsigned sequence, int a, int b) {
  char buf[kAnswerSize];
  encode_answer(buf, kind, sequence, a, b);
  (void)::send(control, buf, sizeof buf, MSG_NOSIGNAL);
}

void send_fd(int control, unsigned sequence, int fd) {
  char buf[kAnswerSize] = {};
  encode_answer(buf, kFd, sequence, 0, 0);
  FdMessage m(buf, sizeof buf);
  msghdr& msg = m.msg;
  cmsghdr* c = CMSG_FIRSTHDR(&msg);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SCM_RIGHTS;
  c->cmsg_len = CMSG_LEN(sizeof(int));
  std::memcpy(CMSG_DATA(c), &fd, sizeof fd);
  (void)::sendmsg(control, &msg, MSG_NOSIGNAL);
}

// ---- overtake's end -----------------------------------------------------------------------------

bool send_request(int control, char kind, unsigned sequence, int arg) {
  char buf[kRequestSize];
  encode_request(buf, kind, sequence, arg);
  return ::send(control, buf, sizeof buf, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof buf);
}

bool receive_answer(int control, unsigned sequence, Message& m, int* fd,
                    std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    int got = -1;
    if (left.count() <= 0 || !receive(control, m, &got, left)) return false;
    if (m.sequence == sequence) {
      if (fd)
        *fd = got;
      else if (got >= 0)
        ::close(got);
      return true;
    }
    if (got >= 0) ::close(got);
  }
}

}  // namespace overtake::sandbox::wire
