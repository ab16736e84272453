#include "overtake/app/program_planner.hpp"

namespace overtake::app {

ExternalPlanner program_planner(const PlannerEntry& entry, const std::filesystem::path&) {
  throw std::runtime_error(entry.name + ": planner programs are not built yet");
}

bool private_network_available(std::string* why) {
  if (why) *why = "not built yet";
  return false;
}

}  // namespace overtake::app
