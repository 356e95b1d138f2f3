"""Reading an ECD text folder's events for the test writers: times kept as their decimal text says."""
import gzip


def text_events(seq_dir, until):
    """(t text, x, y, p) of every event up to UNTIL seconds."""
    with gzip.open(seq_dir + "/events.txt.gz", "rt") as f:
        for line in f:
            t, x, y, p = line.split()
            if float(t) > until:
                return
            yield t, int(x), int(y), int(p)


def seconds_ns(t_text):
    """A decimal time ('12.345678901' s) as whole seconds and nanoseconds, exactly."""
    sec, _, frac = t_text.partition(".")
    return int(sec), int((frac + "000000000")[:9])


def events_us(seq_dir, until):
    """[(t in us, cut), x, y, p] of every event up to UNTIL seconds."""
    return [(s * 1_000_000 + ns // 1000, x, y, p) for (s, ns), x, y, p in
            ((seconds_ns(t), x, y, p) for t, x, y, p in text_events(seq_dir, until))]
