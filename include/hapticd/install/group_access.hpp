// The group that may use what an instance makes for its users (docs/install.md): the system
// group hapticd (sysusers.d/hapticd.conf), whose members run hapticctl and render external
// worlds. One way to hand a file to it, for the control socket and an external world's channel.
#pragma once

#include <string>

namespace hapticd::install {

/// Gives the file at `path` (not followed if a link) to the group `group_name`, unless it is
/// its already (under the unit it is born in it). "" when it is the group's, or `group_name`
/// is empty; else a note for the journal, naming `what` ("control socket PATH"), the group and
/// why not, that only this daemon's user may connect, and where `doc` says more.
std::string give_to_group(const std::string& path, const std::string& group_name,
                          const std::string& what, const std::string& doc);

}  // namespace hapticd::install
