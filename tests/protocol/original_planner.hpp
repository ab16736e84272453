#pragma once
// A tiny planner written the way planners for the original simulator are: it finds the
// JSON by cutting the message from the first '[' to the first '}' plus one character,
// treats any message containing "null" as empty, and parses the cut with nlohmann. Our
// client's messages must survive it.

#include <cmath>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace overtake::protocol::testing {

/// The original convention's cut: "" for an empty (null) message or when there is no JSON.
inline std::string cut_json(std::string_view message) {
  if (message.find("null") != std::string_view::npos) return "";
  const auto open = message.find('[');
  const auto close = message.find('}');
  if (open == std::string_view::npos || close == std::string_view::npos) return "";
  return std::string(message.substr(open, close - open + 2));
}

/// What the tiny planner made of the messages it got.
struct OriginalPlannerStats {
  int full = 0;        ///< telemetry parsed and used
  int empty = 0;       ///< recognised as empty ("null"), answered manual
  int unreadable = 0;  ///< anything that made it stumble (must stay 0)
};

/// Answers one message the way such a planner does: for a full telemetry, its previous path
/// plus points straight ahead along the car's yaw until there are 50, 0.4 m apart; manual for
/// an empty one. Counts into `stats`; returns "" when it could not answer.
inline std::string original_planner_answer(std::string_view message, OriginalPlannerStats& stats) {
  if (message.size() <= 2 || message[0] != '4' || message[1] != '2') return "";
  const std::string s = cut_json(message);
  if (s.empty()) {
    ++stats.empty;
    return R"(42["manual",{}])";
  }
  try {
    const auto j = nlohmann::json::parse(s);
    if (j.at(0).get<std::string>() != "telemetry") {
      ++stats.unreadable;
      return "";
    }
    const auto& data = j.at(1);
    const double car_x = data.at("x").get<double>();
    const double car_y = data.at("y").get<double>();
    const double car_yaw = data.at("yaw").get<double>() * std::numbers::pi / 180.0;
    (void)data.at("speed").get<double>();
    (void)data.at("s").get<double>();
    (void)data.at("d").get<double>();
    (void)data.at("end_path_s").get<double>();
    (void)data.at("end_path_d").get<double>();
    std::vector<double> px = data.at("previous_path_x").get<std::vector<double>>();
    std::vector<double> py = data.at("previous_path_y").get<std::vector<double>>();
    const auto fusion = data.at("sensor_fusion").get<std::vector<std::vector<double>>>();
    for (const auto& row : fusion) {
      if (row.size() != 7) ++stats.unreadable;
    }
    double x = px.empty() ? car_x : px.back();
    double y = py.empty() ? car_y : py.back();
    double yaw = car_yaw;
    if (px.size() >= 2)
      yaw = std::atan2(py.back() - py[py.size() - 2], px.back() - px[px.size() - 2]);
    while (px.size() < 50) {
      x += 0.4 * std::cos(yaw);
      y += 0.4 * std::sin(yaw);
      px.push_back(x);
      py.push_back(y);
    }
    ++stats.full;
    nlohmann::json msg;
    msg["next_x"] = px;
    msg["next_y"] = py;
    return "42[\"control\"," + msg.dump() + "]";
  } catch (const std::exception&) {
    ++stats.unreadable;
    return "";
  }
}

}  // namespace overtake::protocol::testing
