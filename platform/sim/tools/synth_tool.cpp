// beslam_synth_tool: runs `beslam synth` on its own (the same entry point the beslam CLI calls).
#include <iostream>
#include <string>
#include <vector>

#include "beslam/sim/synth.hpp"

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (!args.empty() && args.front() == "synth") args.erase(args.begin());
  return beslam::sim::runSynthCommand(args, std::cout, std::cerr);
}
