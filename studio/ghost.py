"""The studio's ``performed`` method and its ghost: the window the free-root humanoid
performed, beside the window it was asked to perform.

Performing a window is slow (the offline effort's search: about a minute per transition
at the default budget on two cores), so it runs in a thread of its own, one at a time, as
the physics check does; the page shows the asked window and a status line with the time
so far until it is done, then redraws. A newer request while one runs replaces any that
waits (the latest settings are the ones performed next).

Which body is which:

- method ``performed``: the solid body is the performed window; with the ghost ticked the
  translucent one is the asked window (the followed method's, "performed follows").
- any other method with the ghost ticked: the solid body is that method's window (the
  asked one) and the translucent one is what the humanoid performed following it.

Where the body cannot perform the asked window (it fell in it, or the search had to leave
it to stay up: ``performed_fell_in_window``, ``performed_left_window``), the page says so
as a finding, not an error.
"""

from __future__ import annotations

import copy
import threading
import time


def ensure_performer() -> None:
    """Install the humanoid's performer (:func:`controller.offline.performer.perform_transition`)
    as ``performed``'s, unless one is installed already."""
    from upm.transitions.performed import installed_performer

    if installed_performer() is None:
        from controller.offline.performer import install

        install()


def finding(result, asked: str) -> str:
    """The page's lines on how the body performed ``asked``'s window (markdown).

    Parameters
    ----------
    result : upm.transitions.Transition
        The performed transition (its ``performed_*`` diagnostics).
    asked : str
        The followed method's name.
    """
    d = result.diagnostics
    figures = (f"joint error {d.get('performed_joint_error_deg', float('nan')):.1f} deg RMS, "
               f"body error {d.get('performed_body_error_mm', float('nan')):.0f} mm, torque "
               f"at its limit {100 * d.get('performed_torque_saturation_share', 0.0):.1f} % "
               f"of the window, {d.get('performed_wall_s', float('nan')):.0f} s of search")
    if d.get("performed_fell_in_window", 0.0):
        head = f"**finding:** the body cannot perform {asked}'s window: it fell in it"
    elif d.get("performed_left_window", 0.0):
        head = (f"**finding:** the body could not keep to {asked}'s window: it left it to "
                "stay up (the search was in trouble in it)")
    elif d.get("performed_fell", 0.0):
        head = f"the body performed {asked}'s window, and fell after it"
    else:
        head = f"the body performed {asked}'s window without falling"
    return f"{head}  \n{figures}"


def legend(method: str, asked: str, ghosted: bool) -> str:
    """Which body is which (markdown)."""
    if method == "performed":
        solid = f"solid: **performed** (the humanoid following {asked}'s window)"
        return solid + (f"; translucent green: **asked** ({asked}'s window)" if ghosted else "")
    return (f"solid: **asked** ({asked}'s window); translucent green: **performed** (the "
            f"humanoid following it)")


class PerformedGhost:
    """The ``performed`` scenes of a :class:`studio.session.Session`, made off the UI thread.

    Parameters
    ----------
    note : viser GUI markdown handle (or anything with a ``content`` attribute)
        Where the status, the legend and the finding are written.
    on_done : callable
        Called (in the worker thread) when a performance is ready: the studio redraws.
    tick_s : float
        How often the status line's time so far is updated, s.
    """

    def __init__(self, note, on_done, tick_s: float = 1.0):
        self.note = note
        self.on_done = on_done
        self.tick_s = tick_s
        self._running = threading.Lock()  # one performance at a time
        self._state = threading.Condition()
        self._pending = None  # the latest snapshot waiting to be performed
        self._busy = False
        self.failed: dict = {}  # settings key -> error text
        self.closed = False  # the page is gone: a finished performance redraws nothing

    def scenes(self, session):
        """The solid and ghost scenes for the session's settings, and the note.

        Returns
        -------
        (Scene, Scene or None, str)
            While the performance is not ready, the asked scene alone (and a request for
            it); a method other than ``performed`` with the ghost off: the method's scene
            and the compared method's, as before.
        """
        method = session.method
        if method != "performed" and not session.performed_ghost:
            ghost = (session.recompute(session.compare_method)
                     if session.compare_method else None)
            return session.recompute(), ghost, ""
        asked_name = session.asked_method()
        if asked_name == "performed":
            raise ValueError("performed cannot follow performed: choose another method "
                             "in 'performed follows'")
        asked = session.recompute(asked_name)
        key = session.performed_key()
        if key in self.failed:
            return asked, None, f"**performed failed:** {self.failed[key]}"
        done = session.performed_scene()
        if done is None:
            self.request(session)
            return asked, None, (f"performing: the humanoid follows {asked_name}'s window "
                                 "(about a minute at the default search on 2 cores); the "
                                 f"solid body shows the asked window ({asked_name}) until "
                                 "it is done")
        note = legend(method, asked_name, session.performed_ghost)
        if session.compare_method:
            note += "  \n(the ghost shows the performed window, not the ghost method)"
        note += "  \n" + finding(done.result, asked_name)
        if method == "performed":
            return done, (asked if session.performed_ghost else None), note
        return asked, done, note

    def request(self, session) -> None:
        """Perform the session's current settings in the worker (a snapshot of them; a
        request already waiting is replaced)."""
        snapshot = copy.copy(session)
        with self._state:
            self._pending = snapshot
            if self._busy:
                return
            self._busy = True
        threading.Thread(target=self._work, daemon=True).start()

    def _work(self) -> None:
        with self._running:
            while True:
                with self._state:
                    snapshot, self._pending = self._pending, None
                    if snapshot is None:
                        self._busy = False
                        self._state.notify_all()
                        return
                self._perform(snapshot)

    def _perform(self, snapshot) -> None:
        key = snapshot.performed_key()
        start = time.monotonic()
        stop = threading.Event()

        def ticker():
            while not stop.wait(self.tick_s):
                self.note.content = (f"performing {snapshot.asked_method()}'s window on "
                                     f"the humanoid: {time.monotonic() - start:.0f} s so far "
                                     "(about a minute at the default search on 2 cores)")

        ticking = threading.Thread(target=ticker, daemon=True)
        ticking.start()
        try:
            snapshot.perform()
        except Exception as error:  # shown in the page, the studio keeps running
            self.failed[key] = str(error)
        finally:
            stop.set()
            ticking.join()
        if not self.closed:
            self.on_done()

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until no performance runs or waits; False on timeout."""
        with self._state:
            return self._state.wait_for(lambda: not self._busy, timeout)
