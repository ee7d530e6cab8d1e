"""The file's transactions: a WorldFile's `reading()` (one read transaction over a
burst of reads: SQLite's autocommit takes and drops its shared lock per statement)
and `transaction()` (BEGIN IMMEDIATE: one writer at a time, whoever else writes)."""
from __future__ import annotations

import sqlite3


class Reading:
    """BEGIN (deferred: a read transaction once it reads) … END under the file's
    lock, unless a transaction is open already."""

    def __init__(self, wf):
        self.wf, self.began = wf, False

    def __enter__(self):
        wf = self.wf
        wf._lock.acquire()
        try:
            if wf.db is not None and not wf.db.in_transaction:
                wf.db.execute("BEGIN")
                self.began = True
        except BaseException:
            wf._lock.release()
            raise
        return wf

    def __exit__(self, exc_type, exc, tb):
        db = self.wf.db
        try:
            if self.began and db is not None and db.in_transaction:
                db.execute("END")  # a read transaction: nothing to commit
        finally:
            self.began = False
            self.wf._lock.release()
        return False


class Transaction:
    """BEGIN IMMEDIATE … COMMIT under the file's lock; ROLLBACK on any error."""

    def __init__(self, wf):
        self.wf = wf

    def __enter__(self):
        self.wf._writable()
        self.wf._lock.acquire()
        try:
            self.wf.check_path()
            self.wf.db.execute("BEGIN IMMEDIATE")
        except BaseException:
            self.wf._lock.release()
            raise
        return self.wf.db

    def __exit__(self, exc_type, exc, tb):
        db = self.wf.db
        try:
            if exc_type:
                db.execute("ROLLBACK")
            else:
                try:
                    db.execute("COMMIT")
                except sqlite3.Error:
                    # a COMMIT that failed (disk full, I/O error) can leave the
                    # transaction open: end it, so a later save can try again
                    if db.in_transaction:
                        db.execute("ROLLBACK")
                    raise
        finally:
            self.wf._lock.release()
        return False
