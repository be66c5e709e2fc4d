"""The one exception that the command line turns into exit status 2 and one line."""


class InputError(Exception):
    """Bad user input: a missing file, bad TOML, an unknown key, a value out of range.

    The message is one line naming the file, the field and what is allowed.
    """
