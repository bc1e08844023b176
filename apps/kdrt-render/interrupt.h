// Ctrl-C (SIGINT), SIGTERM and SIGHUP stop a run cleanly: the handler only
// records the signal (async-signal-safe); the progress callback and the
// model import's keep_going return false once it is set, the library then
// throws kdrt::Error(Cancelled), and kdrt-render exits 128 + the signal's
// number (130, 143, 129) having written nothing: outputs are committed only
// after the render, and the temporaries of files being written are removed
// as their AtomicFiles go. A second such signal ends the process at once,
// removing those temporaries first (detail::remove_live_temporaries).
// A signal ignored when kdrt-render starts stays ignored. SIGXFSZ (a
// file-size limit, ulimit -f) is ignored: the write then fails with EFBIG,
// which is reported as a failed write naming the file (exit 1).
#pragma once

namespace kdrt::cli {

void install_interrupt_handler();
bool interrupted();
// The first stopping signal that arrived, 0 if none.
int interrupt_signal();
// Throws kdrt::Error(Cancelled) once such a signal has arrived.
void stop_if_interrupted();

}  // namespace kdrt::cli
