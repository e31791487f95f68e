#include "runtime/robot/text_file.hpp"

#include <fstream>
#include <mutex>
#include <sstream>

namespace pbppo::robot {
namespace {

std::mutex g_mu;
std::map<std::string, std::uint64_t>& Reads() {
  static std::map<std::string, std::uint64_t> reads;
  return reads;
}

}  // namespace

Result<std::string> ReadTextFile(const std::string& path) {
  {
    std::lock_guard<std::mutex> lk(g_mu);
    ++Reads()[path];
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return MakeError(ErrorCode::kIo, path + ": cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return MakeError(ErrorCode::kIo, path + ": read error");
  return ss.str();
}

std::map<std::string, std::uint64_t> FileReads() {
  std::lock_guard<std::mutex> lk(g_mu);
  return Reads();
}

}  // namespace pbppo::robot
