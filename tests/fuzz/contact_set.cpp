// Fuzz target: a contact set's bytes as they come off the wire (CDR), read as every receiver
// reads them: deserialized, checked (dds::CheckContactSet), and each finger decoded by the
// contact codec (dds::DecodeFingerContact). A set the checks accept decodes into finite
// contacts, and a decoded contact encodes back into the same finger (the codec's round trip).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <span>

#include "fuzz_support.hpp"
#include "handshare/dds/contact_codec.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/dds/serialization.hpp"

namespace {
void Finding(const char* what, int finger) {
  std::fprintf(stderr, "fuzz: finding: finger %d: %s\n", finger, what);
  std::abort();
}
bool Finite(const handshare::contact::Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace dds = handshare::dds;
  handshare::msg::ContactSet set;
  bool read = false;
  handshare::fuzz::ExpectOnly<dds::SerializationError>([&] {
    dds::Deserialize(std::span<const std::uint8_t>(data, size), set);
    read = true;
  });
  if (!read) return 0;
  const bool accepted = dds::CheckContactSet(set, set.session().to_string()).empty();
  for (int i = 0; i < static_cast<int>(set.fingers().size()); ++i) {
    const auto& f = set.fingers()[i];
    handshare::contact::FingerContact c;
    const bool active = dds::DecodeFingerContact(f, i, 0, c);
    if (active != f.active()) Finding("decode disagrees with the wire's active flag", i);
    if (!active) continue;
    if (accepted && !(Finite(c.p_OC_m) && Finite(c.n_O) && Finite(c.p_OE_m) && Finite(c.u_O_m) && Finite(c.f_O_N) &&
                      std::isfinite(c.depth_m))) {
      Finding("an accepted set decodes into a contact that is not finite", i);
    }
    if (!accepted) continue;
    handshare::msg::FingerContact back;
    dds::EncodeFingerContact(c, f.object_id().to_string(), f.radius_m(), dds::SampleBounds{}.max_displacement_m, back);
    if (!(back == f)) Finding("an accepted finger does not encode back to itself", i);
  }
  return 0;
}
