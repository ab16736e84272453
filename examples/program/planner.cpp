// A planner program for the original simulator's protocol, written the way the course's
// programs are: it reads the map file, listens on port 4567, answers each telemetry with a
// path, and prints a line per message. It keeps a lane, follows the car ahead, and changes
// lanes when it is held up and a neighbouring lane is free.
//
// Build (Debian: libboost-dev, nlohmann-json3-dev):
//   g++ -std=c++17 -O2 planner.cpp -o planner -pthread
// Run it under overtake (a network of its own per run, so runs go in parallel):
//   overtake sim --planner-cmd "./planner ../../data/tracks/default.csv" --planner-cwd
//   examples/program overtake bench --planner-cmd "./planner ../../data/tracks/default.csv"
//   --planner-name mine
//                  --planner-cwd examples/program --policies walkthrough --seeds 1-10

#include <algorithm>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace {

using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;
constexpr double kStep = 0.02;       // s per path point
constexpr double kTopSpeed = 21.9;   // m/s, just under 50 mph
constexpr double kLaneWidth = 4.0;   // m
constexpr double kSpeedStep = 0.09;  // m/s per cycle, well within the acceleration limit

struct Map {
  std::vector<double> x, y, s, dx, dy;
  double length = 6945.554;  // the loop, m
};

Map read_map(const std::string& file) {
  Map m;
  std::ifstream in(file);
  double x, y, s, dx, dy;
  while (in >> x >> y >> s >> dx >> dy) {
    m.x.push_back(x);
    m.y.push_back(y);
    m.s.push_back(s);
    m.dx.push_back(dx);
    m.dy.push_back(dy);
  }
  if (!m.x.empty()) m.length = m.s.back() + std::hypot(m.x[0] - m.x.back(), m.y[0] - m.y.back());
  return m;
}

// Frenet (s, d) to map x, y along the waypoints' polyline and its normals.
void to_xy(const Map& m, double s, double d, double& x, double& y) {
  s = std::fmod(std::fmod(s, m.length) + m.length, m.length);
  std::size_t i = std::upper_bound(m.s.begin(), m.s.end(), s) - m.s.begin();
  i = i == 0 ? m.s.size() - 1 : i - 1;
  const std::size_t j = (i + 1) % m.s.size();
  const double seg = (j == 0 ? m.length : m.s[j]) - m.s[i];
  const double f = seg > 0 ? (s - m.s[i]) / seg : 0.0;
  x = m.x[i] + f * (m.x[j] - m.x[i]) + d * (m.dx[i] + f * (m.dx[j] - m.dx[i]));
  y = m.y[i] + f * (m.y[j] - m.y[i]) + d * (m.dy[i] + f * (m.dy[j] - m.dy[i]));
}

// A natural cubic spline y(x) through points with increasing x.
struct Spline {
  std::vector<double> x, a, b, c, d;
  Spline(std::vector<double> xs, std::vector<double> ys) : x(std::move(xs)), a(std::move(ys)) {
    const std::size_t n = x.size() - 1;
    std::vector<double> h(n), alpha(n + 1, 0.0), l(n + 1, 1.0), mu(n + 1, 0.0), z(n + 1, 0.0);
    b.assign(n, 0.0);
    c.assign(n + 1, 0.0);
    d.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) h[i] = x[i + 1] - x[i];
    for (std::size_t i = 1; i < n; ++i)
      alpha[i] = 3.0 / h[i] * (a[i + 1] - a[i]) - 3.0 / h[i - 1] * (a[i] - a[i - 1]);
    for (std::size_t i = 1; i < n; ++i) {
      l[i] = 2.0 * (x[i + 1] - x[i - 1]) - h[i - 1] * mu[i - 1];
      mu[i] = h[i] / l[i];
      z[i] = (alpha[i] - h[i - 1] * z[i - 1]) / l[i];
    }
    for (std::size_t i = n; i-- > 0;) {
      c[i] = z[i] - mu[i] * c[i + 1];
      b[i] = (a[i + 1] - a[i]) / h[i] - h[i] * (c[i + 1] + 2.0 * c[i]) / 3.0;
      d[i] = (c[i + 1] - c[i]) / (3.0 * h[i]);
    }
  }
  double operator()(double t) const {
    std::size_t i = std::upper_bound(x.begin(), x.end(), t) - x.begin();
    i = std::clamp<std::size_t>(i == 0 ? 0 : i - 1, 0, b.size() - 1);
    const double u = t - x[i];
    return a[i] + u * (b[i] + u * (c[i] + u * d[i]));
  }
};

struct Planner {
  Map map;
  int lane = 1;
  double speed = 0.0;  // m/s wanted at the end of the kept path
  int settle = 0;      // cycles to wait after a lane change

  // The gap (m, signed, across the loop's seam) from s0 to each car in `l`, at time ahead_s.
  std::pair<double, double> gaps(const json& cars, int l, double s0, double ahead_s) const {
    double front = 1e9, back = 1e9;
    for (const auto& c : cars) {
      const double d = c[6];
      if (d < l * kLaneWidth - 0.5 || d > (l + 1) * kLaneWidth + 0.5) continue;
      const double v = std::hypot(double(c[3]), double(c[4]));
      double gap = double(c[5]) + v * ahead_s - s0;
      gap = std::fmod(gap + 1.5 * map.length, map.length) - 0.5 * map.length;
      if (gap >= 0)
        front = std::min(front, gap);
      else
        back = std::min(back, -gap);
    }
    return {front, back};
  }

  json plan(const json& t) {
    std::vector<double> px = t["previous_path_x"], py = t["previous_path_y"];
    const std::size_t keep = std::min<std::size_t>(px.size(), 25);
    px.resize(keep);
    py.resize(keep);
    const double ahead_s = keep * kStep;
    const double s0 = keep ? double(t["s"]) + speed * ahead_s : double(t["s"]);
    const auto [front, back] = gaps(t["sensor_fusion"], lane, s0, ahead_s);
    (void)back;
    const bool held_up = front < 35.0;
    if (held_up && settle == 0) {
      for (const int to : {lane - 1, lane + 1}) {
        if (to < 0 || to > 2) continue;
        const auto [f, b] = gaps(t["sensor_fusion"], to, s0, ahead_s);
        if (f > 45.0 && b > 20.0) {
          lane = to;
          settle = 150;
          break;
        }
      }
    }
    if (settle > 0) --settle;
    if (front < 15.0)
      speed = std::max(0.0, speed - 2.0 * kSpeedStep);
    else if (held_up)
      speed = std::max(0.0, speed - kSpeedStep);
    else
      speed = std::min(kTopSpeed, speed + kSpeedStep);

    // Anchors: the kept path's last two points, then three points ahead in the lane.
    double x0 = t["x"], y0 = t["y"], yaw = double(t["yaw"]) * kPi / 180.0;
    double xb = x0 - std::cos(yaw), yb = y0 - std::sin(yaw);
    if (keep >= 2) {
      x0 = px[keep - 1];
      y0 = py[keep - 1];
      xb = px[keep - 2];
      yb = py[keep - 2];
      yaw = std::atan2(y0 - yb, x0 - xb);
    }
    std::vector<double> ax{xb, x0}, ay{yb, y0};
    for (const double ds : {40.0, 70.0, 100.0}) {
      double x, y;
      to_xy(map, s0 + ds, kLaneWidth * (lane + 0.5), x, y);
      ax.push_back(x);
      ay.push_back(y);
    }
    std::vector<double> lx, ly;  // in the frame of the kept path's end
    for (std::size_t i = 0; i < ax.size(); ++i) {
      lx.push_back((ax[i] - x0) * std::cos(yaw) + (ay[i] - y0) * std::sin(yaw));
      ly.push_back(-(ax[i] - x0) * std::sin(yaw) + (ay[i] - y0) * std::cos(yaw));
    }
    const Spline f(lx, ly);
    const double reach = 30.0, stretch = reach / std::hypot(reach, f(reach));
    double u = 0.0;
    for (std::size_t i = keep; i < 50; ++i) {
      u += std::max(speed, 0.05) * kStep * stretch;
      const double v = f(u);
      px.push_back(x0 + u * std::cos(yaw) - v * std::sin(yaw));
      py.push_back(y0 + u * std::sin(yaw) + v * std::cos(yaw));
    }
    return json{{"next_x", px}, {"next_y", py}};
  }
};

}  // namespace

int main(int argc, char** argv) {
  namespace net = boost::asio;
  namespace ws = boost::beast::websocket;
  const std::string map_file = argc > 1 ? argv[1] : "../../data/tracks/default.csv";
  Planner planner{read_map(map_file)};
  if (planner.map.x.empty()) {
    std::cerr << "cannot read the map " << map_file << "\n";
    return 1;
  }
  net::io_context ioc;
  net::ip::tcp::acceptor acceptor(ioc, {net::ip::tcp::v4(), 4567});
  std::cout << "Listening to port 4567" << std::endl;
  for (;;) {
    net::ip::tcp::socket socket(ioc);
    acceptor.accept(socket);
    ws::stream<net::ip::tcp::socket> stream(std::move(socket));
    stream.accept();
    planner = Planner{planner.map};
    std::cout << "Connected!!!" << std::endl;
    for (;;) {
      boost::beast::flat_buffer buffer;
      boost::system::error_code ec;
      stream.read(buffer, ec);
      if (ec) break;
      const std::string msg = boost::beast::buffers_to_string(buffer.data());
      std::string reply = R"(42["manual",{}])";
      const auto open = msg.find('[');
      if (msg.rfind("42", 0) == 0 && open != std::string::npos &&
          msg.find("null") == std::string::npos) {
        const json event = json::parse(msg.substr(open));
        if (event[0] == "telemetry")
          reply = "42[\"control\"," + planner.plan(event[1]).dump() + "]";
      }
      std::cout << msg.substr(0, 80) << std::endl;
      stream.text(true);
      stream.write(net::buffer(reply));
    }
    std::cout << "Disconnected" << std::endl;
  }
}
