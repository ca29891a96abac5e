"""The JCCL configuration system: definitions (.jdef) and configurations (.jconf)."""
