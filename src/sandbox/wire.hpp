#pragma once
// The keeper's wire (internal to the sandbox target): what overtake and the keeper say to each
// other over their Unix socket pair (SOCK_SEQPACKET: one message per packet), how it is
// encoded, and both ends' sending and receiving. Overtake sends requests and receives
// answers; the keeper receives requests and sends answers. Every answer carries the number of
// the request it answers.
//
// The keeper's end (receive_request, send_answer, send_fd) is async-signal-safe, as the
// keeper must be (async_safe.hpp): system calls on buffers on the stack, nothing allocated.

#include <sys/types.h>

#include <chrono>
#include <cstddef>

namespace overtake::sandbox::wire {

// Requests to the keeper: kind, sequence number, argument.
inline constexpr char kSocket = 'S';  // -> kFd with the descriptor, or kNone
inline constexpr char kStatus = 'W';  // -> kRunning, kExited with the wait status, or kGone
inline constexpr char kStop = 'K';    // (argument: grace in ms) -> kDone, then the keeper exits
inline constexpr char kGo = 'G';      // the first request: overtake holds a pidfd of the keeper now
// Answers: kind, the request's sequence number, two numbers.
inline constexpr char kStarted = 'O';  // to kGo: started
inline constexpr char kFailed = 'E';   // to kGo: failed (step, errno)
inline constexpr char kFd = 'F';
inline constexpr char kNone = 'N';
inline constexpr char kRunning = 'R';
inline constexpr char kExited = 'X';
inline constexpr char kGone = 'Z';  // init ended without telling how the program did
inline constexpr char kDone = 'D';  // (known, status)

inline constexpr std::size_t kRequestSize = 1 + 2 * sizeof(int);
inline constexpr std::size_t kAnswerSize = 1 + 3 * sizeof(int);

/// A request (a: its argument) or an answer (a, b: its two numbers).
struct Message {
  char kind = 0;
  unsigned sequence = 0;
  int a = 0;
  int b = 0;
};

// ---- the keeper's end (async-signal-safe) -------------------------------------------------------

/// Receives one request, blocking. Returns what recv returned: <= 0 when overtake has closed
/// its end (or is gone), less than kRequestSize for a short message (what is missing of `m`
/// is then 0).
ssize_t receive_request(int control, Message& m);

/// Sends an answer (errors ignored: overtake may be gone).
void send_answer(int control, char kind, unsigned sequence, int a = 0, int b = 0);

/// Sends kFd with the descriptor `fd` (a copy: the caller still owns `fd`).
void send_fd(int control, unsigned sequence, int fd);

// ---- overtake's end -----------------------------------------------------------------------------

/// Sends a request; false when it could not be sent whole.
[[nodiscard]] bool send_request(int control, char kind, unsigned sequence, int arg);

/// Receives the answer to request `sequence` within `timeout`, dropping late answers to earlier
/// ones (and the descriptors they carry). A descriptor that came with it goes to `*fd` (closed
/// when `fd` is null). False when none came in time or the keeper is gone.
[[nodiscard]] bool receive_answer(int control, unsigned sequence, Message& m, int* fd,
                                  std::chrono::milliseconds timeout);

}  // namespace overtake::sandbox::wire
