// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/security.h"

#include <tinyxml2.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

namespace panoptes::dds {
namespace {

constexpr std::uintmax_t kMaxSecurityFileBytes = 1U << 20U;  // certificates and documents are a few kB

std::string environment(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr ? std::string(value) : std::string();
}

// The whole of a small file; SecurityError if it is missing, not a file, too large or unreadable.
std::string read_security_file(const std::filesystem::path& path, const std::string& what) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw SecurityError(path.string(), "", what + ": no such file");
  if (!std::filesystem::is_regular_file(path, error))
    throw SecurityError(path.string(), "", what + ": not a regular file");
  if (std::filesystem::file_size(path, error) > kMaxSecurityFileBytes)
    throw SecurityError(path.string(), "", what + ": larger than 1 MiB, not a certificate or document");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SecurityError(path.string(), "", what + ": cannot be read (permissions?)");
  std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw SecurityError(path.string(), "", what + ": read error");
  return content;
}

bool has_pem_block(const std::string& content, const std::string& label) {
  const std::size_t begin = content.find("-----BEGIN " + label + "-----");
  return begin != std::string::npos &&
         content.find("-----END " + label + "-----", begin) != std::string::npos;
}

void check_pem(const std::filesystem::path& path, const std::string& what,
               const std::vector<std::string>& labels) {
  const std::string content = read_security_file(path, what);
  for (const auto& label : labels) {
    if (has_pem_block(content, label)) return;
  }
  throw SecurityError(path.string(), "", what + ": no PEM block '-----BEGIN " + labels.front() + "-----'");
}

// An S/MIME-signed XML document (openssl smime -sign -text): the signed XML part must parse and
// hold `required_element` under <dds>.
void check_signed_document(const std::filesystem::path& path, const std::string& what,
                           const std::string& container, const std::string& required_element) {
  const std::string content = read_security_file(path, what);
  if (content.find("multipart/signed") == std::string::npos ||
      content.find("pkcs7-signature") == std::string::npos)
    throw SecurityError(path.string(), "",
                        what + ": not an S/MIME signed document (sign it with panoptes-security)");
  const std::size_t begin =
      content.find("<?xml") != std::string::npos ? content.find("<?xml") : content.find("<dds");
  const std::size_t end = content.find("</dds>");
  if (begin == std::string::npos || end == std::string::npos || end < begin)
    throw SecurityError(path.string(), "", what + ": the signed part holds no <dds> document");
  const std::string xml = content.substr(begin, end + 6 - begin);
  tinyxml2::XMLDocument document;
  if (document.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    const char* reason = document.ErrorStr();
    throw SecurityError(path.string(), "",
                        what + ": the XML does not parse: " + (reason != nullptr ? reason : "?"));
  }
  const tinyxml2::XMLElement* root = document.FirstChildElement("dds");
  const tinyxml2::XMLElement* section =
      root != nullptr ? root->FirstChildElement(container.c_str()) : nullptr;
  if (section == nullptr || section->FirstChildElement(required_element.c_str()) == nullptr)
    throw SecurityError(path.string(), "", what + ": no <dds><" + container + "><" + required_element + ">");
}

}  // namespace

std::optional<SecurityFiles> resolve_security_files(const SecurityOptions& options) {
  const std::filesystem::path directory = options.directory.empty()
                                              ? std::filesystem::path(environment("PANOPTES_SECURITY_DIR"))
                                              : options.directory;
  const std::string identity =
      options.identity.empty() ? environment("PANOPTES_SECURITY_IDENTITY") : options.identity;
  if (directory.empty() && identity.empty()) return std::nullopt;
  if (directory.empty())
    throw SecurityError("--security-identity", "",
                        "'" + identity +
                            "' given without a security directory (--security-dir or "
                            "PANOPTES_SECURITY_DIR)");
  if (identity.empty())
    throw SecurityError(directory.string(), "",
                        "security directory given without an identity (--security-identity or "
                        "PANOPTES_SECURITY_IDENTITY)");
  if (!std::filesystem::is_directory(directory))
    throw SecurityError(directory.string(), "", "security directory: no such directory");
  if (identity.find('/') != std::string::npos || identity == "." || identity == "..")
    throw SecurityError(directory.string(), "", "identity '" + identity + "': not a name under identities/");
  const std::filesystem::path node = directory / "identities" / identity;
  SecurityFiles files;
  files.identity_ca = directory / "identity_ca.pem";
  files.permissions_ca = directory / "permissions_ca.pem";
  files.governance = directory / "governance.p7s";
  if (std::filesystem::exists(directory / "identity_crl.pem"))
    files.identity_crl = directory / "identity_crl.pem";
  files.certificate = node / "cert.pem";
  files.private_key = node / "key.pem";
  files.permissions = node / "permissions.p7s";
  return files;
}

void check_security_files(const SecurityFiles& files) {
  if (const std::filesystem::path node = files.certificate.parent_path();
      !std::filesystem::is_directory(node))
    throw SecurityError(node.string(), "",
                        "identity: no such directory (panoptes-security issue <dir> <role> <name>)");
  check_pem(files.identity_ca, "identity CA certificate", {"CERTIFICATE"});
  check_pem(files.permissions_ca, "permissions CA certificate", {"CERTIFICATE"});
  if (!files.identity_crl.empty()) check_pem(files.identity_crl, "identity revocation list", {"X509 CRL"});
  check_pem(files.certificate, "identity certificate", {"CERTIFICATE"});
  if (has_pem_block(read_security_file(files.private_key, "private key"), "ENCRYPTED PRIVATE KEY"))
    throw SecurityError(files.private_key.string(), "",
                        "private key: encrypted; DDS Security needs it unencrypted");
  check_pem(files.private_key, "private key", {"EC PRIVATE KEY", "PRIVATE KEY"});
  check_signed_document(files.governance, "governance", "domain_access_rules", "domain_rule");
  check_signed_document(files.permissions, "permissions", "permissions", "grant");
}

std::vector<std::pair<std::string, std::string>> security_properties(const SecurityFiles& files) {
  const auto uri = [](const std::filesystem::path& path) {
    return "file://" + std::filesystem::absolute(path).lexically_normal().string();
  };
  const std::string auth = "dds.sec.auth.builtin.PKI-DH.";
  const std::string access = "dds.sec.access.builtin.Access-Permissions.";
  std::vector<std::pair<std::string, std::string>> properties = {
      {"dds.sec.auth.plugin", "builtin.PKI-DH"},
      {auth + "identity_ca", uri(files.identity_ca)},
      {auth + "identity_certificate", uri(files.certificate)},
      {auth + "private_key", uri(files.private_key)},
      {"dds.sec.access.plugin", "builtin.Access-Permissions"},
      {access + "permissions_ca", uri(files.permissions_ca)},
      {access + "governance", uri(files.governance)},
      {access + "permissions", uri(files.permissions)},
      {"dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC"},
  };
  if (!files.identity_crl.empty()) properties.emplace_back(auth + "identity_crl", uri(files.identity_crl));
  return properties;
}

std::string describe_security_files(const SecurityFiles& files) {
  std::ostringstream out;
  out << "identity CA " << files.identity_ca.string() << ", certificate " << files.certificate.string()
      << ", private key " << files.private_key.string() << ", permissions CA "
      << files.permissions_ca.string() << ", governance " << files.governance.string() << ", permissions "
      << files.permissions.string();
  if (!files.identity_crl.empty()) out << ", revocation list " << files.identity_crl.string();
  return out.str();
}

}  // namespace panoptes::dds
