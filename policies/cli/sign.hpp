// `pbppo sign BLOB --key KEY.pem [--out SIG]`: a detached Ed25519 signature beside the blob
// ("x.sig", runtime/policy/signature.hpp). `pbppo verify BLOB (--robot ROBOT | --key PUB.pem...)`:
// the check a controller makes before arming, against the robot's trusted keys or the keys given.
// Exit 0: signed / verified; 1: refused (the message says why); 2: usage.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace pbppo::cli {

struct SignOptions {
  std::string blob, key, out;
};
struct VerifyOptions {
  std::string blob, robot, signature;
  std::vector<std::string> keys;
};

CLI::App* AddSign(CLI::App& app, SignOptions& o);
CLI::App* AddVerify(CLI::App& app, VerifyOptions& o);
int Sign(const SignOptions& o);
int Verify(const VerifyOptions& o);

}  // namespace pbppo::cli
