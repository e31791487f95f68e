#include "runtime/transport/dds/dds_security.hpp"
#include "runtime/policy/openssl_handles.hpp"

#include <openssl/bio.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>

#include <filesystem>
#include <memory>

namespace pbppo::dds {
namespace {

struct Files {
  std::string ca, governance, certificate, key, permissions;
};

Files FilesOf(const DdsSecurity& s) {
  const std::filesystem::path d(s.dir);
  return {(d / "ca.pem").string(), (d / "governance.p7s").string(), (d / (s.identity + ".pem")).string(),
          (d / (s.identity + "_key.pem")).string(), (d / (s.identity + "_permissions.p7s")).string()};
}

Error SecError(const std::string& what) {
  return MakeError(ErrorCode::kInvalidValue, "dds security: " + what);
}

using ossl::Bio;
using Cert = ossl::Handle<X509, X509_free>;
using Store = ossl::Handle<X509_STORE, X509_STORE_free>;
using StoreCtx = ossl::Handle<X509_STORE_CTX, X509_STORE_CTX_free>;
using Pkcs7 = ossl::Handle<PKCS7, PKCS7_free>;

std::string TimeText(const ASN1_TIME* t) {
  Bio b(BIO_new(BIO_s_mem()));
  ASN1_TIME_print(b.get(), t);
  char* data = nullptr;
  const long n = BIO_get_mem_data(b.get(), &data);
  return std::string(data, static_cast<std::size_t>(n));
}

Result<Cert> ReadCert(const std::string& path, const char* what) {
  Bio b(BIO_new_file(path.c_str(), "r"));
  if (!b) return SecError(std::string(what) + " '" + path + "' cannot be read");
  Cert c(PEM_read_bio_X509(b.get(), nullptr, nullptr, nullptr));
  if (!c) return SecError(std::string(what) + " '" + path + "' is not a PEM certificate");
  return c;
}

// An S/MIME document signed by the CA, its content unaltered.
Status CheckSigned(const std::string& path, const char* what, X509_STORE* store) {
  Bio b(BIO_new_file(path.c_str(), "r"));
  if (!b) return SecError(std::string(what) + " '" + path + "' cannot be read");
  BIO* content = nullptr;
  Pkcs7 p7(SMIME_read_PKCS7(b.get(), &content));
  Bio content_owner(content);
  if (!p7) return SecError(std::string(what) + " '" + path + "' is not an S/MIME signed document");
  Bio out(BIO_new(BIO_s_mem()));
  if (PKCS7_verify(p7.get(), nullptr, store, content, out.get(), PKCS7_TEXT) != 1)
    return SecError(std::string(what) + " '" + path +
                    "' does not verify against the CA: altered after signing, or signed by another CA");
  return {};
}

}  // namespace

Status CheckDdsSecurity(const DdsSecurity& s) {
  if (!s.enabled()) return {};
  if (s.identity.empty()) return SecError("no identity (the participant's certificate name) for '" + s.dir + "'");
  const Files f = FilesOf(s);
  for (const std::string* p : {&f.ca, &f.governance, &f.certificate, &f.key, &f.permissions}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(*p, ec)) return SecError("'" + *p + "' is missing");
  }
  auto ca = ReadCert(f.ca, "CA certificate");
  if (!ca) return std::move(ca).error();
  auto cert = ReadCert(f.certificate, "identity certificate");
  if (!cert) return std::move(cert).error();
  const X509* c = cert->get();
  if (X509_cmp_current_time(X509_get0_notAfter(c)) < 0)
    return SecError("identity certificate '" + f.certificate + "' expired on " + TimeText(X509_get0_notAfter(c)));
  if (X509_cmp_current_time(X509_get0_notBefore(c)) > 0)
    return SecError("identity certificate '" + f.certificate + "' is not valid before " +
                    TimeText(X509_get0_notBefore(c)));
  Store store(X509_STORE_new());
  X509_STORE_add_cert(store.get(), ca->get());
  StoreCtx ctx(X509_STORE_CTX_new());
  X509_STORE_CTX_init(ctx.get(), store.get(), cert->get(), nullptr);
  if (X509_verify_cert(ctx.get()) != 1)
    return SecError("identity certificate '" + f.certificate + "' is not signed by the CA '" + f.ca +
                    "': " + X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get())));
  {
    Bio b(BIO_new_file(f.key.c_str(), "r"));
    ossl::Pkey key(b ? PEM_read_bio_PrivateKey(b.get(), nullptr, nullptr, nullptr) : nullptr);
    if (!key) return SecError("private key '" + f.key + "' is not an unencrypted PEM key");
    if (X509_check_private_key(cert->get(), key.get()) != 1)
      return SecError("private key '" + f.key + "' does not belong to '" + f.certificate + "'");
  }
  if (auto st = CheckSigned(f.governance, "governance", store.get()); !st) return st;
  if (auto st = CheckSigned(f.permissions, "permissions", store.get()); !st) return st;
  return {};
}

std::vector<std::pair<std::string, std::string>> SecurityProperties(const DdsSecurity& s) {
  const Files f = FilesOf(s);
  auto file = [](const std::string& p) { return "file://" + std::filesystem::absolute(p).string(); };
  return {{"dds.sec.auth.plugin", "builtin.PKI-DH"},
          {"dds.sec.auth.builtin.PKI-DH.identity_ca", file(f.ca)},
          {"dds.sec.auth.builtin.PKI-DH.identity_certificate", file(f.certificate)},
          {"dds.sec.auth.builtin.PKI-DH.private_key", file(f.key)},
          {"dds.sec.access.plugin", "builtin.Access-Permissions"},
          {"dds.sec.access.builtin.Access-Permissions.permissions_ca", file(f.ca)},
          {"dds.sec.access.builtin.Access-Permissions.governance", file(f.governance)},
          {"dds.sec.access.builtin.Access-Permissions.permissions", file(f.permissions)},
          {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"}};
}

}  // namespace pbppo::dds
