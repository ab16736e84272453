#include "overtake/app/cli.hpp"

int main(int argc, char** argv) {
  return overtake::app::run_cli(argc, argv);
}
