// Definitions an executable gives in place of Fast DDS 2.9.1's own. The library calls these
// functions through its PLT or its vtables, so the definition in an executable that links
// handshare::dds wins: the lease-check guard (lease_race_guard.cpp) and the discovery endpoints'
// repair timing (edp_heartbeat.cpp). Each runs the library's own definition too.
#pragma once

namespace handshare::dds::detail {

// The library's definition of `symbol` (the next one after this executable's). When it is not
// found the process cannot do what the library would: it stops, naming `what`.
void* LibraryDefinition(const char* symbol, const char* what);

// True when this process resolves `symbol` to a definition outside the object that holds
// `library_definition` (that is, this executable's takes the library's place).
bool OverrideInEffect(const char* symbol, void* library_definition);

}  // namespace handshare::dds::detail
