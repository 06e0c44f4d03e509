"""What a run's files hold and how they are read: CSV column contract, run folders, field method.

The lowest layer of ``studies``: every other subpackage may use it, it uses none of them.
"""
