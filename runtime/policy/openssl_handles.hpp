// OpenSSL objects owned by std::unique_ptr (set-up code: blob signatures, DDS Security's files).
#pragma once

#include <openssl/bio.h>
#include <openssl/evp.h>

#include <memory>

namespace pbppo::ossl {

template <typename T, void (*Free)(T*)>
struct Deleter {
  void operator()(T* p) const noexcept { Free(p); }
};
template <typename T, void (*Free)(T*)>
using Handle = std::unique_ptr<T, Deleter<T, Free>>;

using Bio = Handle<BIO, BIO_free_all>;
using Pkey = Handle<EVP_PKEY, EVP_PKEY_free>;
using MdCtx = Handle<EVP_MD_CTX, EVP_MD_CTX_free>;

}  // namespace pbppo::ossl
