"""planefmt.container.recent.Recent: the encoder's kept segments, walks and bodies."""

from __future__ import annotations

import threading

from planefmt.container.recent import Recent


def test_keeps_the_most_recently_used_and_makes_a_value_once():
    made = []
    kept = Recent(2)

    def make(k):
        return lambda: made.append(k) or k * 10

    assert [kept.get(k, make(k)) for k in (1, 2, 1, 3, 1, 2)] == [10, 20, 10, 30, 10, 20]
    # 1 used again before 3 came, so 2 was dropped, then 3 dropped for 2
    assert made == [1, 2, 3, 2]
    kept.clear()
    assert kept.get(1, make(1)) == 10 and made[-1] == 1


def test_threads_that_drop_and_read_one_another_s_keys_get_their_own_values():
    kept: Recent[int] = Recent(1)
    errors = []

    def run(base):
        try:
            for i in range(20000):
                k = base + i % 3
                assert kept.get(k, lambda: k) == k
        except Exception as exc:  # a KeyError from a key dropped between lookup and read fails the test
            errors.append(exc)

    threads = [threading.Thread(target=run, args=(b,)) for b in (0, 100, 200, 300)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors[:3]
