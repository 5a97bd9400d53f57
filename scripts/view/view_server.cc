#include "scripts/view/view_server.h"

#include <stdexcept>
#include <thread>

#include <httplib.h>

#include "scripts/view/view_assets.h"

namespace mrslam::view {

namespace {

constexpr char kHost[] = "127.0.0.1";
// A comment line this often keeps an idle event stream open and notices a client that left.
constexpr auto kKeepAlive = std::chrono::seconds(5);

// One client's event stream: the newest frame whenever there is one, then a pause; it ends once
// the hub is closed and its last frame sent.
httplib::ContentProviderWithoutLength EventStream(FrameHub* hub, std::chrono::milliseconds min_frame_period) {
  return [hub, min_frame_period, version = std::uint64_t{0}](std::size_t /*offset*/, httplib::DataSink& sink) mutable {
    std::string frame;
    if (!hub->WaitNewer(&version, &frame, kKeepAlive)) {
      if (hub->closed()) {
        sink.done();
        return true;
      }
      static constexpr char kComment[] = ": keep-alive\n\n";
      return sink.write(kComment, sizeof(kComment) - 1);
    }
    const std::string event = "data: " + frame + "\n\n";
    if (!sink.write(event.data(), event.size())) return false;
    hub->Pause(min_frame_period);
    return true;
  };
}

}  // namespace

struct ViewServer::Impl {
  ViewContent content;
  std::chrono::milliseconds min_frame_period{0};
  httplib::Server server;
  std::thread thread;

  void Route() {
    server.Get("/", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(std::string(PageHtml()), "text/html; charset=utf-8");
    });
    server.Get("/view.js", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(std::string(ViewJs()), "text/javascript; charset=utf-8");
    });
    server.Get("/info", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(content.info_json, "application/json");
    });
    if (content.hub != nullptr) {
      server.Get("/events", [this](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-cache");
        res.set_chunked_content_provider("text/event-stream", EventStream(content.hub, min_frame_period));
      });
    } else {
      server.Get("/steps", [this](const httplib::Request&, httplib::Response& res) {
        res.set_content(content.steps_json, "application/json");
      });
    }
  }
};

ViewServer::ViewServer(ViewContent content, std::chrono::milliseconds min_frame_period)
    : impl_(std::make_unique<Impl>()) {
  impl_->content = std::move(content);
  impl_->min_frame_period = min_frame_period;
  impl_->Route();
}

ViewServer::~ViewServer() { Stop(); }

int ViewServer::Start(int port) {
  int bound = port;
  if (port == 0) {
    bound = impl_->server.bind_to_any_port(kHost);
  } else if (!impl_->server.bind_to_port(kHost, port)) {
    bound = -1;
  }
  if (bound <= 0) throw std::runtime_error("cannot listen on " + std::string(kHost) + ":" + std::to_string(port));
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
  return bound;
}

void ViewServer::Stop() {
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

}  // namespace mrslam::view
