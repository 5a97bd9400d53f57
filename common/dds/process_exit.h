#pragma once

namespace mrslam::dds {

// Ends the process with `code` once its DDS entities are gone (every Participant destroyed):
// flushes spdlog, Fast DDS's log and the standard streams, and exits without running static
// destructors. Fast DDS 2.9's DomainParticipantFactory sleeps 100 ms in its destructor (after
// deleting the participants left, none here), so every process of a run would otherwise end
// 100 ms after its work. Built with a sanitizer it exits normally, so that the leak check at
// exit still runs.
[[noreturn]] void ExitProcess(int code);

}  // namespace mrslam::dds
