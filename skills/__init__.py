"""The built-in skill families (cable routing, lab automation), registered under the
``cellengine.skills`` entry point group in pyproject.toml like any other package's."""
