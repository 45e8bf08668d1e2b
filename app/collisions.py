"""Contacts grouped into collisions: what the close-up zooms on and the animation slows down for."""

from __future__ import annotations

import twoball


def collisions(contacts: list[twoball.ContactInterval]) -> list[list[twoball.ContactInterval]]:
    """The contacts grouped into collisions, in time order.

    A contact belongs to the current collision if it starts less than the collision's duration
    so far after the collision's end: the balls' several contacts during one floor contact are
    one collision, the lower ball's next floor bounce, long after, starts another.
    """
    groups: list[list[twoball.ContactInterval]] = []
    for contact in sorted(contacts, key=lambda c: c.start):
        if groups:
            start, stop = groups[-1][0].start, max(c.end for c in groups[-1])
            if contact.start <= stop + (stop - start):
                groups[-1].append(contact)
                continue
        groups.append([contact])
    return groups


def first_collision(contacts: list[twoball.ContactInterval]) -> list[twoball.ContactInterval]:
    """The contacts of the first collision (:func:`collisions`)."""
    return collisions(contacts)[0]
