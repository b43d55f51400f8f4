// `coaxid design`: experiment design (issue 16). Predicts the parameter std
// a planned experiment (flight and balance scenarios) would give before it
// is flown, designs a multisine excitation for the parameters the user
// names within the pilot's limits, and the balance holds to add.
#pragma once

namespace coaxid {

int RunDesign();

}  // namespace coaxid
