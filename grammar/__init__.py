"""The AMIL grammar, shipped as package data (`amil.lark`)."""
