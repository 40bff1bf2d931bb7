// SPDX-License-Identifier: Apache-2.0
// DDS Security for a Bus (docs/security.md): where a node's certificates and signed documents are,
// the checks made before a participant joins, and the Fast DDS properties that enable the builtin
// plugins (PKI-DH authentication, Access-Permissions, AES-GCM-GMAC). The files come from
// deploy/security/panoptes-security; their locations are always given, never assumed.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "panoptes/errors.h"

namespace panoptes::dds {

// A security file that is missing, unreadable or malformed, a secure profile without security
// options, or a participant that DDS Security refused. Programs exit 2 (bad input) on it and never
// fall back to an unsecured participant.
class SecurityError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

struct SecurityOptions {
  // The studio directory made by panoptes-security (identity_ca.pem, permissions_ca.pem,
  // governance.p7s, optional identity_crl.pem, identities/<identity>/). Empty: $PANOPTES_SECURITY_DIR.
  std::filesystem::path directory;
  // The node's identity, a directory under identities/. Empty: $PANOPTES_SECURITY_IDENTITY.
  std::string identity;
};

// The files of one secured participant.
struct SecurityFiles {
  std::filesystem::path identity_ca;
  std::filesystem::path permissions_ca;
  std::filesystem::path identity_crl;  // empty: no revocation list
  std::filesystem::path governance;
  std::filesystem::path certificate;
  std::filesystem::path private_key;
  std::filesystem::path permissions;
};

// The files `options` (or the environment) name; nullopt when neither names a security directory.
// Throws SecurityError for a directory without an identity or the reverse.
std::optional<SecurityFiles> resolve_security_files(const SecurityOptions& options);

// Checks without cryptography that every file exists, is readable and has the expected form: PEM
// certificates, key and CRL; governance and permissions as S/MIME-signed XML that parses, with a
// domain rule and a grant. Throws SecurityError naming the file and the reason. The signatures
// and the certificate chain are checked by Fast DDS when the participant is created.
void check_security_files(const SecurityFiles& files);

// Checks that the governance has a domain rule and the permissions an allow rule for `domain`
// (0..232). Fast DDS 2.9 creates a participant on a domain its governance does not cover, without
// the governance's protection, and then refuses its every topic as not granted. Throws
// SecurityError naming the document, the domain and the domains the document covers.
void check_security_domain(const SecurityFiles& files, int domain);

// The participant properties that enable the builtin DDS Security plugins with `files`.
std::vector<std::pair<std::string, std::string>> security_properties(const SecurityFiles& files);

// The one-line summary printed with a refused participant: which files were used.
std::string describe_security_files(const SecurityFiles& files);

}  // namespace panoptes::dds
