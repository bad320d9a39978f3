#include "view/replay.hpp"

#include <cmath>
#include <functional>
#include <string_view>

#include "io/image_io.hpp"
#include "io/json_reader.hpp"

using nlohmann::json;
using penumbra::Error;
using penumbra::Expected;
using penumbra::Status;
using penumbra::io::JsonFailure;
using penumbra::io::JsonReader;
using penumbra::io::Range;
namespace sl = penumbra::spaceland;

namespace viewer {

namespace {

// A setting a set event may name: how it is read from JSON (checked) and written back.
struct Field {
  const char* name;
  std::function<void(const JsonReader&, const json&, const std::string&, Settings&)> read;
  std::function<json(const Settings&)> write;
  bool sun = false;  // only where the scene has a sun
};

template <class E>
E enum_value(const JsonReader& r, const json& j, const std::string& path,
             std::initializer_list<E> values) {
  std::string names;
  if (j.is_string())
    for (E v : values)
      if (j.get<std::string>() == sl::to_string(v)) return v;
  for (E v : values) names += std::string(names.empty() ? "" : ", ") + sl::to_string(v);
  r.expected(path, "one of " + names, j);
}

const std::vector<Field>& fields() {
  static const std::vector<Field> list = {
      {"method",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.method = enum_value(r, j, p,
                                       {sl::Method::ssrc, sl::Method::spwi, sl::Method::surface,
                                        sl::Method::grid, sl::Method::pt});
       },
       [](const Settings& s) { return json(sl::to_string(s.options.method)); }},
      {"bounces",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.bounces = r.integer(j, p, 1, 64);
       },
       [](const Settings& s) { return json(s.options.bounces); }},
      {"temporal",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.temporal = r.integer(j, p, 0, 1024);
       },
       [](const Settings& s) { return json(s.temporal); }},
      {"grid_slabs",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.grid_slabs = r.integer(j, p, 0, 1 << 20);
       },
       [](const Settings& s) { return json(s.grid_slabs); }},
      {"exposure",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         if (j.is_string() && j.get<std::string>() == "auto")
           s.exposure.reset();
         else if (j.is_number())
           s.exposure = r.number(j, p, Range::any);
         else
           r.expected(p, "an exposure in EV or \"auto\"", j);
         if (s.exposure && std::fabs(*s.exposure) > 64)
           r.fail_at(p, "expected an exposure within +-64 EV");
       },
       [](const Settings& s) { return s.exposure ? json(*s.exposure) : json("auto"); }},
      {"scale",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         const float v = r.number(j, p, Range::unit);
         if (v != 0 && v < 1.0f / 16)
           r.fail_at(p, "expected 0 (automatic) or a scale in [1/16, 1], found " +
                            penumbra::io::format_number(v));
         s.scale = v;
       },
       [](const Settings& s) { return json(s.scale); }},
      {"target_ms",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         const float v = r.number(j, p, Range::positive);
         if (v < 1 || v > 10000)
           r.fail_at(
               p, "expected a frame time in 1..10000 ms, found " + penumbra::io::format_number(v));
         s.target_ms = v;
       },
       [](const Settings& s) { return json(s.target_ms); }},
      {"upscale",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         if (!j.is_string() || (j != "guided" && j != "bilinear"))
           r.expected(p, "\"guided\" or \"bilinear\"", j);
         s.guided = j == "guided";
       },
       [](const Settings& s) { return json(s.guided ? "guided" : "bilinear"); }},
      {"threads",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.threads = r.integer(j, p, 0, 1024);
       },
       [](const Settings& s) { return json(s.options.threads); }},
      {"sun_azimuth",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.sun_azimuth = std::remainder(r.number(j, p, Range::any), 360.0f);
         s.sun_moved = true;
       },
       [](const Settings& s) { return json(s.sun_azimuth); }, true},
      {"sun_elevation",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         const float v = r.number(j, p, Range::any);
         if (v < -90 || v > 90)
           r.fail_at(p, "expected an elevation in -90..90 degrees, found " +
                            penumbra::io::format_number(v));
         s.sun_elevation = v;
         s.sun_moved = true;
       },
       [](const Settings& s) { return json(s.sun_elevation); }, true},
      {"ssrc.directions",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.ssrc.directions = r.integer(j, p, 1, 1024);
       },
       [](const Settings& s) { return json(s.options.ssrc.directions); }},
      {"ssrc.sectors",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.ssrc.sectors = r.integer(j, p, 8, 32);
       },
       [](const Settings& s) { return json(s.options.ssrc.sectors); }},
      {"ssrc.offscreen",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.ssrc.offscreen =
             enum_value(r, j, p, {sl::SsrcOffscreen::sky, sl::SsrcOffscreen::world});
       },
       [](const Settings& s) { return json(sl::to_string(s.options.ssrc.offscreen)); }},
      {"spwi.directions",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.spwi.directions = r.integer(j, p, 4, 4096);
       },
       [](const Settings& s) { return json(s.options.spwi.directions); }},
      {"spwi.merge",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.spwi.merge =
             enum_value(r, j, p,
                        {sl::SpwiMerge::bilinear, sl::SpwiMerge::bilateral,
                         sl::SpwiMerge::bilinear3d, sl::SpwiMerge::fix, sl::SpwiMerge::minmax});
       },
       [](const Settings& s) { return json(sl::to_string(s.options.spwi.merge)); }},
      {"grid.probe_spacing",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.grid.probe_spacing = r.integer(j, p, 1, 64);
       },
       [](const Settings& s) { return json(s.options.grid.probe_spacing); }},
      {"grid.directions",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.grid.directions = r.integer(j, p, 4, 4096);
       },
       [](const Settings& s) { return json(s.options.grid.directions); }},
      {"surface.texels",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.surface.texels = std::uint64_t(r.integer(j, p, 64, 1 << 28));
       },
       [](const Settings& s) { return json(s.options.surface.texels); }},
      {"surface.directions",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.surface.directions = r.integer(j, p, 4, 4096);
       },
       [](const Settings& s) { return json(s.options.surface.directions); }},
      {"pt.spp",
       [](const JsonReader& r, const json& j, const std::string& p, Settings& s) {
         s.options.pt.spp = r.integer(j, p, 1, 1 << 20);
       },
       [](const Settings& s) { return json(s.options.pt.spp); }},
  };
  return list;
}

void read_set(const JsonReader& r, const json& set, const std::string& where, Settings& s,
              bool has_sun) {
  if (!set.is_object()) r.expected(where, "an object of settings", set);
  for (const auto& [key, value] : set.items()) {
    if (JsonReader::is_comment_key(key)) continue;
    const Field* f = nullptr;
    for (const Field& c : fields())
      if (key == c.name) f = &c;
    const std::string path = where + "." + key;
    if (!f) {
      std::string names;
      for (const Field& c : fields()) names += std::string(names.empty() ? "" : ", ") + c.name;
      r.fail_at(path, "unknown setting; expected one of " + names);
    }
    if (f->sun && !has_sun) r.fail_at(path, "the scene has no sun to move");
    f->read(r, value, path, s);
  }
  // The ranges and combinations, as render checks them: the method's, and those of each method
  // whose options the event names (checked as if it were picked).
  if (Status st = sl::check_options(s.options); !st) r.fail_at(where, st.error().message);
  for (const sl::MethodInfo& m : sl::methods())
    for (const auto& [key, value] : set.items())
      if (key.starts_with(std::string(m.name) + ".")) {
        sl::RenderOptions o = s.options;
        o.method = m.method;
        if (Status st = sl::check_options(o); !st) r.fail_at(where, st.error().message);
      }
}

}  // namespace

Status apply_set(const json& set, const std::string& where, Settings& s, bool has_sun) {
  // The file named in `where` already; the reader's own name is left empty.
  try {
    Settings next = s;
    read_set(JsonReader(""), set, where, next, has_sun);
    s = next;
    return {};
  } catch (const JsonFailure& f) {
    std::string m = f.message;
    if (m.starts_with(": ")) m = m.substr(2);
    return Error{m};
  }
}

Expected<Replay> load_replay(const std::string& path) {
  Expected<std::string> text = penumbra::io::read_text(path, "the replay file");
  if (!text) return text.error();
  try {
    const json doc = penumbra::io::parse_json(*text, path);
    const JsonReader r(path);
    if (!doc.is_object()) r.expected("(document)", "an object with \"events\"", doc);
    r.check_keys(doc, "", {"penumbra_view", "events"});
    const json& version = r.require(doc, "", "penumbra_view", "the replay format version, 1");
    if (r.integer(version, "penumbra_view", 1, 1) != 1) r.fail_at("penumbra_view", "expected 1");
    const json& events = r.require(doc, "", "events", "an array of events");
    if (!events.is_array()) r.expected("events", "an array of events", events);
    Replay out;
    // Settings are checked against a scene when they are applied; here their form only.
    Settings scratch;
    for (std::size_t i = 0; i < events.size(); ++i) {
      const std::string p = "events[" + std::to_string(i) + "]";
      const json& e = events[i];
      // One event key, beside any comment keys.
      std::string kind;
      int kinds = 0;
      if (e.is_object())
        for (const auto& [key, value] : e.items())
          if (!JsonReader::is_comment_key(key)) {
            kind = key;
            ++kinds;
          }
      if (kinds != 1)
        r.expected(p, "an object with one of \"camera\", \"move\", \"set\", \"wait\"", e);
      Event ev;
      const json& v = e[kind];
      const std::string q = p + "." + kind;
      if (kind == "camera") {
        ev.kind = Event::Kind::camera;
        if (!v.is_object()) r.expected(q, "an object with position, yaw and pitch", v);
        r.check_keys(v, q, {"position", "yaw", "pitch"});
        const json& pos = r.require(v, q, "position", "3 numbers");
        if (!pos.is_array() || pos.size() != 3) r.expected(q + ".position", "3 numbers", pos);
        for (int k = 0; k < 3; ++k)
          ev.position[k] = r.number(pos[k], q + ".position[" + std::to_string(k) + "]", Range::any);
        ev.yaw = r.number(r.require(v, q, "yaw", "degrees"), q + ".yaw", Range::any);
        ev.pitch = r.number(r.require(v, q, "pitch", "degrees"), q + ".pitch", Range::any);
        if (ev.pitch < -89 || ev.pitch > 89)
          r.fail_at(q + ".pitch",
                    "expected -89..89 degrees, found " + penumbra::io::format_number(ev.pitch));
      } else if (kind == "move") {
        ev.kind = Event::Kind::move;
        if (!v.is_object()) r.expected(q, "an object with by and turn", v);
        r.check_keys(v, q, {"by", "turn"});
        if (v.contains("by")) {
          const json& by = v["by"];
          if (!by.is_array() || by.size() != 3)
            r.expected(q + ".by", "3 numbers: right, up, forward", by);
          for (int k = 0; k < 3; ++k)
            ev.by[k] = r.number(by[k], q + ".by[" + std::to_string(k) + "]", Range::any);
        }
        if (v.contains("turn")) {
          const std::array<float, 2> t = r.point(v["turn"], q + ".turn");
          ev.turn_yaw = t[0];
          ev.turn_pitch = t[1];
        }
      } else if (kind == "set") {
        ev.kind = Event::Kind::set;
        read_set(r, v, q, scratch, true);
        ev.set = v;
      } else if (kind == "wait") {
        ev.kind = Event::Kind::wait;
        if (!v.is_object()) r.expected(q, "an object with frames", v);
        r.check_keys(v, q, {"frames"});
        ev.frames =
            r.integer(r.require(v, q, "frames", "a number of frames"), q + ".frames", 1, 100000);
      } else {
        r.fail_at(p, "unknown event \"" + kind + "\"; expected camera, move, set or wait");
      }
      out.events.push_back(std::move(ev));
    }
    return out;
  } catch (const JsonFailure& f) {
    return Error{f.message};
  }
}

json diff_settings(const Settings& s, const Settings& from, bool has_sun) {
  json d = json::object();
  for (const Field& f : fields()) {
    if (f.sun && !has_sun) continue;
    json now = f.write(s);
    if (now != f.write(from)) d[f.name] = std::move(now);
  }
  return d.empty() ? json() : d;
}

std::string replay_json(const Replay& r) {
  json events = json::array();
  for (const Event& e : r.events) {
    switch (e.kind) {
      case Event::Kind::camera:
        events.push_back({{"camera",
                           {{"position", {e.position.x, e.position.y, e.position.z}},
                            {"yaw", e.yaw},
                            {"pitch", e.pitch}}}});
        break;
      case Event::Kind::move:
        events.push_back(
            {{"move", {{"by", {e.by.x, e.by.y, e.by.z}}, {"turn", {e.turn_yaw, e.turn_pitch}}}}});
        break;
      case Event::Kind::set:
        events.push_back({{"set", e.set}});
        break;
      case Event::Kind::wait:
        events.push_back({{"wait", {{"frames", e.frames}}}});
        break;
    }
  }
  return json{{"penumbra_view", 1}, {"events", events}}.dump(1) + "\n";
}

}  // namespace viewer
