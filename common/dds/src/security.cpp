// SPDX-License-Identifier: Apache-2.0
#include "panoptes/dds/security.h"

#include <tinyxml2.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

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

// The XML of an S/MIME-signed document (openssl smime -sign -text), parsed into `document`.
void parse_signed_document(const std::filesystem::path& path, const std::string& what,
                           tinyxml2::XMLDocument& document) {
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
  if (document.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    const char* reason = document.ErrorStr();
    throw SecurityError(path.string(), "",
                        what + ": the XML does not parse: " + (reason != nullptr ? reason : "?"));
  }
}

// A signed document whose XML must hold `required_element` under <dds><container>.
void check_signed_document(const std::filesystem::path& path, const std::string& what,
                           const std::string& container, const std::string& required_element) {
  tinyxml2::XMLDocument document;
  parse_signed_document(path, what, document);
  const tinyxml2::XMLElement* root = document.FirstChildElement("dds");
  const tinyxml2::XMLElement* section =
      root != nullptr ? root->FirstChildElement(container.c_str()) : nullptr;
  if (section == nullptr || section->FirstChildElement(required_element.c_str()) == nullptr)
    throw SecurityError(path.string(), "", what + ": no <dds><" + container + "><" + required_element + ">");
}

// Whether a <domains> element covers `domain`, read as Fast DDS 2.9 reads it (CommonParser.cpp,
// is_domain_in_set in Permissions.cpp): <id>N</id> is N; <id_range> runs from <min> (0 without)
// to <max>, and is <min> alone without <max> or with <max>0</max>. Appends each set to `seen`
// ("0..230").
bool domains_cover(const tinyxml2::XMLElement* domains, unsigned domain, std::vector<std::string>& seen) {
  bool covered = false;
  for (const tinyxml2::XMLElement* set = domains != nullptr ? domains->FirstChildElement() : nullptr;
       set != nullptr; set = set->NextSiblingElement()) {
    unsigned low = 0;
    unsigned high = 0;
    const std::string name = set->Name();
    const tinyxml2::XMLElement* min = name == "id" ? set : set->FirstChildElement("min");
    const tinyxml2::XMLElement* max = name == "id" ? nullptr : set->FirstChildElement("max");
    if ((name != "id" && name != "id_range") ||
        (min != nullptr && min->QueryUnsignedText(&low) != tinyxml2::XML_SUCCESS) ||
        (max != nullptr && max->QueryUnsignedText(&high) != tinyxml2::XML_SUCCESS))
      continue;  // Fast DDS refuses the document; its own error says why
    if (high == 0) high = low;
    seen.push_back(low == high ? std::to_string(low) : std::to_string(low) + ".." + std::to_string(high));
    covered = covered || (domain >= low && domain <= high);
  }
  return covered;
}

// The <domains> of every rule of a governance (<domain_access_rules><domain_rule>) or permissions
// document (<permissions><grant><allow_rule>).
std::vector<const tinyxml2::XMLElement*> rule_domains(const tinyxml2::XMLDocument& document,
                                                      bool permissions) {
  std::vector<const tinyxml2::XMLElement*> found;
  const tinyxml2::XMLElement* root = document.FirstChildElement("dds");
  const char* section_name = permissions ? "permissions" : "domain_access_rules";
  const tinyxml2::XMLElement* section = root != nullptr ? root->FirstChildElement(section_name) : nullptr;
  if (section == nullptr) return found;
  for (const auto* element = section->FirstChildElement(); element != nullptr;
       element = element->NextSiblingElement()) {
    if (!permissions) {
      found.push_back(element->FirstChildElement("domains"));
      continue;
    }
    for (const auto* rule = element->FirstChildElement("allow_rule"); rule != nullptr;
         rule = rule->NextSiblingElement("allow_rule"))
      found.push_back(rule->FirstChildElement("domains"));
  }
  return found;
}

// That a rule of the signed governance or permissions document covers `domain`; SecurityError
// naming the document, the domain and the domains it does cover.
void check_document_domain(const std::filesystem::path& path, const std::string& what, bool permissions,
                           unsigned domain) {
  tinyxml2::XMLDocument document;
  parse_signed_document(path, what, document);
  std::vector<std::string> seen;
  for (const tinyxml2::XMLElement* domains : rule_domains(document, permissions))
    if (domains_cover(domains, domain, seen)) return;
  std::string list;
  for (const auto& each : seen) list += (list.empty() ? "" : ", ") + each;
  throw SecurityError(path.string(), "",
                      what + ": no " + (permissions ? "allow_rule" : "domain_rule") + " covers DDS domain " +
                          std::to_string(domain) + " (it covers " + (list.empty() ? "none" : list) + "; " +
                          (permissions ? "Fast DDS would refuse every topic"
                                       : "Fast DDS would join without the governance's protection") +
                          "). A studio made by panoptes-security covers domains 0..230 (docs/security.md, "
                          "\"Domains\")");
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

void check_security_domain(const SecurityFiles& files, int domain) {
  const auto id = static_cast<unsigned>(domain);
  check_document_domain(files.governance, "governance", false, id);
  check_document_domain(files.permissions, "permissions", true, id);
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
      // ECDH+prime256v1 for the handshakes this participant starts, which Cyclone DDS can read
      // (docs/security.md, "Cyclone DDS"): Fast DDS 2.10.7, 2.14.5, 3.0.2, 3.1.1 and 3.2 read it; Debian's
      // 2.9.1 ignores it and always starts with DH+MODP-2048-256.
      {auth + "preferred_key_agreement", "ECDH"},
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
