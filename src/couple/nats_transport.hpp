#pragma once
// The mediator transport: publish/subscribe through a NATS server (the source's mediator,
// over TCP: reliable and ordered per channel). URL: nats://HOST:PORT[?prefix=P]; every
// channel C travels on subject P.C (default prefix "bs"), so several runs can share one
// server under different prefixes. Model code and the wrapper do not change.
#include <memory>
#include <string>
#include <vector>

#include "couple/transport.hpp"

namespace builtscene::couple {

// Recovery: a JetStream stream keeps the history of the run's data channels (on subjects
// P.C), at most `max_per_channel` messages each (the oldest are dropped). A transport on
// the same URL then offers subscribe_from_start() and last_stored(). Throws Failure.
void create_history_stream(const std::string& url, const std::vector<std::string>& channels,
                           int64_t max_per_channel);

// Throws InputError for a malformed URL, Failure when the server cannot be reached.
std::unique_ptr<Transport> make_nats_transport(const std::string& url);

// "nats://HOST:PORT" without the query (what the NATS client and nats-server take).
std::string nats_server_address(const std::string& url);

bool is_nats_url(const std::string& url);

}  // namespace builtscene::couple
