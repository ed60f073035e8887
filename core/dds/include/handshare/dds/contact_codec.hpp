#pragma once
/// The contact codec: the one place that turns the one contact type (contact::FingerContact,
/// frame O, force on the object) into the IDL's finger of a ContactSet and back. Nothing else
/// reads or writes msg::FingerContact's vectors: the haptic bridge encodes its hand's contacts
/// here, and every receiver (session::PeerContacts, the sample checks, the deadband, the grasp
/// claims) decodes them here. The field names are the same on both sides (p_OC_m, n_O, p_OE_m,
/// u_O_m, f_O_N, depth_m), so a check's reason names both. Not real-time (bridge threads).
#include <cstdint>
#include <string_view>

#include "handshare/contact/finger_contact.hpp"
#include "handshare/dds/messages.hpp"

namespace handshare::dds {

/// Writes contact `c` of a fingertip of radius `radius_m` on object `object_id` (the scene's
/// id; c.object is this process's index and does not travel) into `out`; an inactive contact
/// (c.object < 0) is written inactive with zero vectors. A displacement or depth beyond
/// `max_displacement_m` (a fingertip pushed far through an object, or after a stall) goes out
/// clamped to it in its own direction: receivers drop a set over the bound
/// (SampleBounds::max_displacement_m), and with it the grasp and the body it carries.
void EncodeFingerContact(const contact::FingerContact& c, std::string_view object_id, double radius_m,
                         double max_displacement_m, msg::FingerContact& out);

/// Reads finger `finger` of a set into `out`, on object `object`: the receiver's index of
/// in.object_id() (found in its own models; the codec does not know them). False, and `out`
/// inactive, when the finger is not active or `object` < 0.
bool DecodeFingerContact(const msg::FingerContact& in, std::int32_t finger, contact::ObjectId object,
                         contact::FingerContact& out) noexcept;

}  // namespace handshare::dds
