// Ctrl-C (SIGINT) stops a render cleanly: the handler only sets an atomic
// flag (async-signal-safe); the progress callback returns false once it is
// set, the library then throws kdrt::Error(Cancelled), and kdrt-render exits
// 130 having written nothing (outputs are committed only after the render).
// The handler is installed with SA_RESETHAND: a second Ctrl-C kills at once.
// A SIGINT ignored when kdrt-render starts stays ignored.
#pragma once

namespace kdrt::cli {

void install_interrupt_handler();
bool interrupted();

}  // namespace kdrt::cli
