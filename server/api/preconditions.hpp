#pragma once
// Versions on every mutable object (issue 26): reads answer `ETag: "v<N>"` and a `version` field;
// a write names the version it read, in `If-Match: "v<N>"` or a `version` member of its body. A
// stale one is answered 412 version_conflict with the stored object (error.current), never
// applied; a write to an existing object that names none is answered 428 precondition_required
// (two operators must never overwrite each other blindly). Creating names no version.
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "server/http/http_types.hpp"

namespace rover::api {

// The version a request names: If-Match ("v7" or v7; one strong tag as sent, not W/"v7", "v07" or "*"), else the body's
// `version` (a non-negative integer; `body` may be null). 400 naming If-Match / version for a
// malformed one, or when both are given and differ. nullopt when neither is given.
std::optional<long long> namedVersion(const http::Request& req, const nlohmann::json* body = nullptr);

// namedVersion, required: 428 precondition_required (field If-Match) when absent. `what` names the
// object in the message ("the zones of this map").
long long requiredVersion(const http::Request& req, const nlohmann::json* body, const std::string& what);

// 412 version_conflict (field If-Match) with the stored object in error.current.
http::ApiError versionConflict(const std::string& what, long long named, long long current,
                               nlohmann::json currentObject);

// `"v<N>"`, the ETag of version N.
std::string etagOf(long long version);
// `r` with its ETag header.
http::Response withETag(http::Response r, long long version);

}  // namespace rover::api
