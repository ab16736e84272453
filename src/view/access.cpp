// Who the view server answers and what a request names: pure functions over header values
// and targets, apart from the server so that tests and the fuzzer reach them without a
// socket (and without compiling the server).

#include <algorithm>
#include <cctype>
#include <charconv>
#include <optional>
#include <string>
#include <string_view>

#include <boost/asio/ip/address_v4.hpp>
#include <boost/asio/ip/address_v6.hpp>

#include "overtake/view/server.hpp"

namespace overtake::view {
namespace {

constexpr std::string_view kLoopbackNames[] = {"localhost", "127.0.0.1", "[::1]"};

bool same_text(std::string_view a, std::string_view b) {  // ASCII, without case
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

// A Host header (or the part of an Origin after the scheme) as a name and a port: `name`,
// `name:port`, `[v6]` or `[v6]:port`, the name made only of characters that a host name or an
// address may hold, the port of digits, from 1 to 65535. Nullopt when it is anything else.
struct HostPort {
  std::string_view name;  // brackets kept for IPv6
  std::optional<unsigned> port;
};
std::optional<HostPort> split_host(std::string_view host) {
  HostPort out;
  std::string_view rest;
  if (!host.empty() && host[0] == '[') {
    const std::size_t close = host.find(']');
    if (close == std::string_view::npos || close < 2) return std::nullopt;
    out.name = host.substr(0, close + 1);
    rest = host.substr(close + 1);
    for (const char c : out.name.substr(1, out.name.size() - 2)) {
      if (!std::isxdigit(static_cast<unsigned char>(c)) && c != ':' && c != '.')
        return std::nullopt;
    }
  } else {
    const std::size_t colon = host.find(':');
    out.name = host.substr(0, colon);
    rest = colon == std::string_view::npos ? std::string_view{} : host.substr(colon);
    if (out.name.empty()) return std::nullopt;
    for (const char c : out.name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_')
        return std::nullopt;
    }
  }
  if (!rest.empty()) {
    const std::string_view digits = rest.substr(1);
    unsigned port = 0;
    const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), port);
    if (rest[0] != ':' || digits.empty() || digits.size() > 5 || r.ec != std::errc{} ||
        r.ptr != digits.data() + digits.size() || port == 0 || port > 65535) {
      return std::nullopt;
    }
    out.port = port;
  }
  return out;
}

// An IPv4 address in dotted form, or an IPv6 one in brackets.
bool is_address_literal(std::string_view name) {
  boost::system::error_code ec;
  if (name.size() > 2 && name.front() == '[') {
    (void)boost::asio::ip::make_address_v6(std::string(name.substr(1, name.size() - 2)), ec);
  } else {
    (void)boost::asio::ip::make_address_v4(std::string(name), ec);
  }
  return !ec;
}

}  // namespace

std::string host_for_url(const std::string& host) {
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;
}

bool is_loopback_name(std::string_view name) {
  return std::any_of(std::begin(kLoopbackNames), std::end(kLoopbackNames),
                     [&](std::string_view n) { return same_text(n, name); });
}

ViewRoute route_target(std::string_view target, const ViewContent& content) {
  const std::string_view path = target.substr(0, target.find('?'));
  ViewResource resource = ViewResource::none;
  if (path == "/" || path == "/index.html") {
    resource = ViewResource::page;
  } else if (path == kReplayUrlPath && content.replay) {
    resource = ViewResource::replay;
  } else if (path == kLiveUrlPath && content.live) {
    resource = ViewResource::live;
  }
  return {resource, path};
}

bool host_allowed(std::string_view host, std::string_view bound_host) {
  const auto hp = split_host(host);
  if (!hp) return false;
  for (const std::string_view name : kLoopbackNames) {
    if (same_text(hp->name, name)) return true;
  }
  if (bound_host.empty()) return false;
  if (same_text(hp->name, host_for_url(std::string(bound_host)))) return true;
  // Bound to every address: any of this machine's addresses may be in the URL, and only a
  // name (not an address) can be rebound to another machine.
  return (bound_host == "0.0.0.0" || bound_host == "::") && is_address_literal(hp->name);
}

bool same_origin(std::string_view origin, std::string_view host) {
  constexpr std::string_view kScheme = "http://";
  if (origin.size() <= kScheme.size() || !same_text(origin.substr(0, kScheme.size()), kScheme))
    return false;
  const auto o = split_host(origin.substr(kScheme.size()));
  const auto h = split_host(host);
  constexpr unsigned kHttpPort = 80;
  return o && h && same_text(o->name, h->name) &&
         o->port.value_or(kHttpPort) == h->port.value_or(kHttpPort);
}

}  // namespace overtake::view
