"""The representative run behind ``pneumaquad demo`` and its report sections."""
