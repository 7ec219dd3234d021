"""Exception hierarchy. Messages name the value, the expected form and a fix."""


class AssistError(Exception):
    """Base class of every error assist3d raises on purpose."""


class ConfigError(AssistError):
    """A configuration value or command-line option is invalid."""


class AssetError(AssistError):
    """An asset file or catalog is missing, corrupt or unusable."""


class PlacementError(AssistError):
    """A layout search could not satisfy a request."""


class DataError(AssistError):
    """A dataset file is missing, truncated or malformed."""


class RenderError(AssistError):
    """Ray casting or fusion failed."""


class LLMError(AssistError):
    """An LLM endpoint failed or answered something unusable."""
